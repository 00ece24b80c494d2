// Mesh decimation through VTK's vtkDecimatePro (decimation.hpp). The only file that includes
// VTK: the mesh goes in as vtkPolyData with each vertex's input index as point data, and comes
// out as our TriangleMesh plus the surviving indices.
#include "analysis/preprocess/decimation.hpp"

#include <vtkCallbackCommand.h>
#include <vtkCellArray.h>
#include <vtkCellArrayIterator.h>
#include <vtkCommand.h>
#include <vtkDecimatePro.h>
#include <vtkDoubleArray.h>
#include <vtkIdTypeArray.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkSmartPointer.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <string>
#include <utility>

#include "analysis/core/parallel.hpp"
#include "analysis/core/triangle_bvh.hpp"

namespace springscan::analysis {
namespace {

using Triangles = std::vector<std::array<std::uint32_t, 3>>;

constexpr const char* kInputIdName = "springscan_input_id";
// vtkIdType is 64-bit in Debian's VTK, but our indices are 32-bit; 2^31 leaves room for both.
constexpr std::size_t kMaxElements = std::size_t{1} << 31;
// Beyond this no scan is in mm, and VTK's tolerances (a fraction of the bounding box) and
// squared errors lose all precision.
constexpr double kMaxCoordinateMm = 1e9;

Error bad_setting(const std::string& field, double value, const std::string& rule) {
  return fail(ErrorCode::kInvalidSettings, "settings: reduction.mesh_decimation." + field + " = " +
                                               std::to_string(value) + " (" + rule + ")");
}

bool in_range(double v, double lo, double hi) { return std::isfinite(v) && v >= lo && v <= hi; }

// VTK reports filter errors and warnings through vtkOutputWindow (stderr) unless an observer
// takes them; library code does not print (STYLE.md §5), so they are collected here instead.
struct VtkMessages {
  std::string errors;
  static void on_event(vtkObject*, unsigned long event, void* client, void* call_data) {
    auto* self = static_cast<VtkMessages*>(client);
    const char* text = static_cast<const char*>(call_data);
    if (event == vtkCommand::ErrorEvent && text) self->errors += text;
  }
};

// Per vertex: 1 if some triangle uses it.
std::vector<std::uint8_t> used_mask(const TriangleMesh& mesh) {
  std::vector<std::uint8_t> used(mesh.vertices.size(), 0);
  for (const auto& t : mesh.triangles)
    for (std::uint32_t v : t) used[v] = 1;
  return used;
}

// The vertices some triangle uses, in input order. Only these go to VTK: it derives its
// geometric tolerance from the bounds of all the points it is given, used or not (below).
std::vector<std::uint32_t> used_vertices(const TriangleMesh& mesh) {
  const std::vector<std::uint8_t> used = used_mask(mesh);
  std::vector<std::uint32_t> out;
  for (std::uint32_t i = 0; i < mesh.vertices.size(); ++i)
    if (used[i]) out.push_back(i);
  return out;
}

// The mesh as vtkPolyData: the used vertices only, each with its input index as point data.
vtkSmartPointer<vtkPolyData> to_vtk(const TriangleMesh& mesh) {
  const std::vector<std::uint32_t> used = used_vertices(mesh);
  std::vector<vtkIdType> vtk_index(mesh.vertices.size(), -1);
  vtkNew<vtkDoubleArray> coords;
  coords->SetNumberOfComponents(3);
  coords->SetNumberOfTuples(static_cast<vtkIdType>(used.size()));
  vtkNew<vtkIdTypeArray> input_id;
  input_id->SetName(kInputIdName);
  input_id->SetNumberOfValues(static_cast<vtkIdType>(used.size()));
  for (std::size_t i = 0; i < used.size(); ++i) {
    const auto id = static_cast<vtkIdType>(i);
    coords->SetTypedTuple(id, mesh.vertices[used[i]].data());
    input_id->SetValue(id, used[i]);
    vtk_index[used[i]] = id;
  }
  vtkNew<vtkIdTypeArray> offsets, connectivity;
  offsets->SetNumberOfValues(static_cast<vtkIdType>(mesh.triangles.size() + 1));
  connectivity->SetNumberOfValues(static_cast<vtkIdType>(3 * mesh.triangles.size()));
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    offsets->SetValue(static_cast<vtkIdType>(t), static_cast<vtkIdType>(3 * t));
    for (std::size_t c = 0; c < 3; ++c)
      connectivity->SetValue(static_cast<vtkIdType>(3 * t + c), vtk_index[mesh.triangles[t][c]]);
  }
  offsets->SetValue(static_cast<vtkIdType>(mesh.triangles.size()),
                    static_cast<vtkIdType>(3 * mesh.triangles.size()));
  vtkNew<vtkPoints> points;
  points->SetData(coords);
  vtkNew<vtkCellArray> polys;
  polys->SetData(offsets, connectivity);
  auto poly = vtkSmartPointer<vtkPolyData>::New();
  poly->SetPoints(points);
  poly->SetPolys(polys);
  poly->GetPointData()->AddArray(input_id);
  return poly;
}

// The paper's criterion (§2): distance to the average plane, absolute, accumulated over the
// deletions so that it bounds the distance to the original surface; no splitting, so the
// topology (holes, the contour) stays and no vertex is duplicated.
void configure(vtkDecimatePro& filter, const DecimationSettings& s) {
  filter.SetTargetReduction(s.target_reduction);
  filter.SetFeatureAngle(s.feature_angle_deg);
  filter.SetBoundaryVertexDeletion(s.boundary_vertex_deletion ? 1 : 0);
  filter.SetErrorIsAbsolute(1);
  // vtkDecimatePro queues squared distances (to the average plane, or to the line of a contour
  // or crease) and compares them with AbsoluteError as given: so the bound goes in squared.
  filter.SetAbsoluteError(s.max_error_mm * s.max_error_mm);
  filter.AccumulateErrorOn();
  filter.PreserveTopologyOn();
  filter.SplittingOff();
  filter.PreSplitMeshOff();
  filter.SetOutputPointsPrecision(vtkAlgorithm::DOUBLE_PRECISION);
}

// The output mesh in our types; `kept` maps the output's points back to the input. Points the
// filter left without a triangle are dropped (they were deleted; VTK may keep their slots).
Expected<DecimationResult> from_vtk(vtkPolyData& out, const TriangleMesh& in) {
  auto* ids = vtkIdTypeArray::SafeDownCast(out.GetPointData()->GetArray(kInputIdName));
  if (!ids || ids->GetNumberOfValues() != out.GetNumberOfPoints())
    return fail(ErrorCode::kInternal, "mesh decimation: VTK dropped the input vertex ids");
  DecimationResult result;
  std::vector<std::uint32_t> output_index(static_cast<std::size_t>(out.GetNumberOfPoints()),
                                          std::numeric_limits<std::uint32_t>::max());
  auto cells = vtk::TakeSmartPointer(out.GetPolys()->NewIterator());
  for (cells->GoToFirstCell(); !cells->IsDoneWithTraversal(); cells->GoToNextCell()) {
    vtkIdType count = 0;
    const vtkIdType* corners = nullptr;
    cells->GetCurrentCell(count, corners);
    if (count != 3) return fail(ErrorCode::kInternal, "mesh decimation: VTK returned a polygon");
    std::array<std::uint32_t, 3> triangle{};
    for (int c = 0; c < 3; ++c) {
      // VTK has been seen (fuzzing) to return corner -1 on degenerate input: refuse, never index.
      const vtkIdType corner = corners[c];
      const vtkIdType input =
          corner >= 0 && corner < out.GetNumberOfPoints() ? ids->GetValue(corner) : -1;
      if (input < 0 || static_cast<std::size_t>(input) >= in.vertices.size())
        return fail(ErrorCode::kAnalysisFailed,
                    "mesh decimation: VTK returned a triangle with vertex " +
                        std::to_string(corner) + " (a degenerate mesh?)");
      std::uint32_t& slot = output_index[static_cast<std::size_t>(corner)];
      if (slot == std::numeric_limits<std::uint32_t>::max()) {
        slot = static_cast<std::uint32_t>(result.kept.size());
        result.kept.push_back(static_cast<std::uint32_t>(input));
      }
      triangle[static_cast<std::size_t>(c)] = slot;
    }
    result.mesh.triangles.push_back(triangle);
  }
  result.mesh.vertices.reserve(result.kept.size());
  for (std::uint32_t k : result.kept) result.mesh.vertices.push_back(in.vertices[k]);
  return result;
}

// Vertices no triangle uses pass through: they are scan points the decimation has no
// neighbourhood for, not surface it may simplify.
void keep_isolated(const TriangleMesh& in, DecimationResult& result) {
  const std::vector<std::uint8_t> used = used_mask(in);
  for (std::uint32_t i = 0; i < in.vertices.size(); ++i) {
    if (used[i]) continue;
    ++result.isolated_vertices;
    result.kept.push_back(i);
    result.mesh.vertices.push_back(in.vertices[i]);
  }
}

// The largest distance of a deleted vertex to the reduced mesh (per block, then the maximum:
// the same figure whatever the thread count).
double max_deviation(const TriangleMesh& in, const DecimationResult& result, int threads) {
  std::vector<std::uint8_t> kept(in.vertices.size(), 0);
  for (std::uint32_t k : result.kept) kept[k] = 1;
  const TriangleBvh bvh(result.mesh.vertices, result.mesh.triangles);
  std::vector<double> block_max(block_count(in.vertices.size()), 0.0);
  parallel_blocks(in.vertices.size(), threads, [&](std::size_t b, std::size_t lo, std::size_t hi) {
    double worst = 0.0;
    for (std::size_t i = lo; i < hi; ++i) {
      if (kept[i]) continue;
      const auto foot = bvh.nearest(in.vertices[i]);
      if (foot) worst = std::max(worst, foot->squared_distance);
    }
    block_max[b] = worst;
  });
  const double worst =
      block_max.empty() ? 0.0 : *std::max_element(block_max.begin(), block_max.end());
  return std::sqrt(worst);
}

// One vtkDecimatePro run, and the distance of the deleted vertices to its result.
Expected<DecimationResult> run_decimate_pro(vtkPolyData& input, const TriangleMesh& mesh,
                                            const DecimationSettings& settings) {
  vtkNew<vtkDecimatePro> filter;
  configure(*filter, settings);
  VtkMessages messages;
  vtkNew<vtkCallbackCommand> observer;
  observer->SetClientData(&messages);
  observer->SetCallback(&VtkMessages::on_event);
  filter->AddObserver(vtkCommand::ErrorEvent, observer);
  filter->AddObserver(vtkCommand::WarningEvent, observer);
  filter->SetInputData(&input);
  filter->Update();
  if (!messages.errors.empty())
    return fail(ErrorCode::kAnalysisFailed, "mesh decimation (VTK): " + messages.errors);
  auto result = from_vtk(*filter->GetOutput(), mesh);
  if (!result) return result.error();
  keep_isolated(mesh, *result);
  result->input_triangles = mesh.triangles.size();
  result->achieved_reduction =
      1.0 - static_cast<double>(result->mesh.triangles.size()) / mesh.triangles.size();
  result->max_deviation_mm = max_deviation(mesh, *result, settings.threads);
  return result;
}

}  // namespace

Expected<bool> validate(const DecimationSettings& s) {
  if (!in_range(s.target_reduction, 0.0, 0.99))
    return bad_setting("target_reduction", s.target_reduction, "0 to 0.99");
  if (!in_range(s.feature_angle_deg, 1e-6, 180.0))
    return bad_setting("feature_angle_deg", s.feature_angle_deg, "> 0 and <= 180");
  if (!in_range(s.max_error_mm, 1e-9, 1000.0))
    return bad_setting("max_error_mm", s.max_error_mm, "> 0 and <= 1000");
  if (s.threads < 0 || s.threads > 1024)
    return bad_setting("threads", s.threads, "0 to 1024; 0 = all cores");
  return true;
}

namespace {

// vtkDecimatePro needs an oriented manifold: every directed edge (u to v) in at most one
// triangle, and no two triangles on the same three vertices (either winding). A repeated
// triangle, triangles wound against their neighbours, or a third triangle on an edge break
// that, and VTK then crashes (GetCellEdgeNeighbors, RemoveReferenceToCell; found by fuzzing)
// instead of reporting it.
std::optional<Error> find_repeated_triangle(const Triangles& triangles) {
  std::vector<std::pair<std::array<std::uint32_t, 3>, std::size_t>> sorted;
  sorted.reserve(triangles.size());
  for (std::size_t t = 0; t < triangles.size(); ++t) {
    auto key = triangles[t];
    std::sort(key.begin(), key.end());
    sorted.emplace_back(key, t);
  }
  std::sort(sorted.begin(), sorted.end());
  for (std::size_t i = 1; i < sorted.size(); ++i)
    if (sorted[i].first == sorted[i - 1].first)
      return fail("mesh: triangles " + std::to_string(sorted[i - 1].second) + " and " +
                  std::to_string(sorted[i].second) + " have the same three vertices");
  return std::nullopt;
}

// vtkDecimatePro takes 1e-5 of its input's bounding-box diagonal as the length below which
// geometry is degenerate, and collapses such triangles into ones that name a vertex twice; it
// then reads vertex -1 (out of bounds, seen by fuzzing and valgrind) and crashes. That happens
// when the box is about 1e5 times the mesh's edges, which only a stray vertex far from the
// surface makes: a connected scan as long as 1e4 of its edges already has 1e6+ vertices. The
// limit below leaves a factor 10 from that. Unused vertices never go to VTK (to_vtk).
constexpr double kMaxBoxToMedianEdge = 1e4;

std::optional<Error> find_stray_scale(const TriangleMesh& mesh) {
  Vec3 lo = Vec3::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  std::vector<double> edges;
  edges.reserve(3 * mesh.triangles.size());
  for (const auto& t : mesh.triangles)
    for (std::size_t c = 0; c < 3; ++c) {
      const Vec3& a = mesh.vertices[t[c]];
      lo = lo.cwiseMin(a);
      hi = hi.cwiseMax(a);
      edges.push_back((a - mesh.vertices[t[(c + 1) % 3]]).norm());
    }
  const auto middle = edges.begin() + static_cast<std::ptrdiff_t>(edges.size() / 2);
  std::nth_element(edges.begin(), middle, edges.end());
  const double median_edge = *middle, box = (hi - lo).norm();
  if (median_edge > 0.0 && box <= kMaxBoxToMedianEdge * median_edge) return std::nullopt;
  return fail("mesh: its triangles span " + std::to_string(box) + " mm, more than 10^4 times " +
              "their median edge (" + std::to_string(median_edge) +
              " mm): a stray vertex far from the surface? (the decimation cannot resolve the "
              "triangles at that scale)");
}

std::optional<Error> find_repeated_edge(const Triangles& triangles) {
  std::vector<std::pair<std::uint64_t, std::size_t>> edges;
  edges.reserve(3 * triangles.size());
  for (std::size_t t = 0; t < triangles.size(); ++t)
    for (std::size_t c = 0; c < 3; ++c)
      edges.emplace_back(std::uint64_t{triangles[t][c]} << 32 | triangles[t][(c + 1) % 3], t);
  std::sort(edges.begin(), edges.end());
  for (std::size_t i = 1; i < edges.size(); ++i) {
    if (edges[i].first != edges[i - 1].first) continue;
    const std::uint64_t edge = edges[i].first;
    return fail("mesh: triangles " + std::to_string(edges[i - 1].second) + " and " +
                std::to_string(edges[i].second) + " both run edge " + std::to_string(edge >> 32) +
                "-" + std::to_string(edge & 0xFFFFFFFFu) +
                " the same way (a repeated triangle, inconsistent winding, or more than two "
                "triangles on one edge)");
  }
  return std::nullopt;
}

}  // namespace

Expected<bool> check_mesh(const TriangleMesh& mesh) {
  if (mesh.triangles.empty()) return fail("mesh: no triangles to decimate");
  if (mesh.vertices.size() >= kMaxElements || mesh.triangles.size() >= kMaxElements)
    return fail("mesh: " + std::to_string(mesh.vertices.size()) + " vertices and " +
                std::to_string(mesh.triangles.size()) + " triangles (at most 2^31 each)");
  for (std::size_t i = 0; i < mesh.vertices.size(); ++i) {
    if (!mesh.vertices[i].allFinite())
      return fail("mesh: vertex " + std::to_string(i) + " is not finite (NaN or Inf)");
    if (mesh.vertices[i].cwiseAbs().maxCoeff() > kMaxCoordinateMm)
      return fail("mesh: vertex " + std::to_string(i) + " lies " +
                  std::to_string(mesh.vertices[i].cwiseAbs().maxCoeff()) +
                  " mm out (more than 1e9 mm: not a scan in mm)");
  }
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    const auto& tri = mesh.triangles[t];
    for (std::uint32_t v : tri)
      if (v >= mesh.vertices.size())
        return fail("mesh: triangle " + std::to_string(t) + " names vertex " + std::to_string(v) +
                    ", past the " + std::to_string(mesh.vertices.size()) + " vertices");
    if (tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2])
      return fail("mesh: triangle " + std::to_string(t) + " names vertex " +
                  std::to_string(tri[0] == tri[1] ? tri[0] : tri[2]) + " twice");
  }
  if (auto repeated = find_repeated_triangle(mesh.triangles)) return *repeated;
  if (auto repeated = find_repeated_edge(mesh.triangles)) return *repeated;
  if (auto stray = find_stray_scale(mesh)) return *stray;
  return true;
}

Expected<DecimationResult> decimate_mesh(const TriangleMesh& mesh,
                                         const DecimationSettings& settings) {
  if (auto valid = validate(settings); !valid) return valid.error();
  if (auto valid = check_mesh(mesh); !valid) return valid.error();
  const auto input = to_vtk(mesh);
  return run_decimate_pro(*input, mesh, settings);
}

Expected<DecimatedScan> decimate_scan(const PointCloud& cloud, const Triangles& triangles,
                                      const DecimationSettings& settings) {
  TriangleMesh mesh;
  mesh.vertices = cloud.points;
  mesh.triangles = triangles;
  auto result = decimate_mesh(mesh, settings);
  if (!result) return result.error();
  DecimatedScan out;
  out.cloud = select(cloud, result->kept);
  out.result = std::move(result).value();
  return out;
}

}  // namespace springscan::analysis
