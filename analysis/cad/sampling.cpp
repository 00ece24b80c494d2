// Area-weighted sampling of the tessellation, lifted onto the exact surfaces.
#include "analysis/cad/sampling.hpp"

#include <BRepAdaptor_Surface.hxx>
#include <BRepLProp_SLProps.hxx>
#include <Standard_Failure.hxx>
#include <algorithm>
#include <cmath>
#include <random>

#include "analysis/cad/internal.hpp"

namespace springscan::analysis {
namespace {

struct FaceTriangles {
  std::vector<std::size_t> triangles;  // indices into mesh.triangles
  std::vector<double> cumulative_area;
  double area() const { return cumulative_area.empty() ? 0.0 : cumulative_area.back(); }
};

std::vector<FaceTriangles> group_by_face(const CadMesh& mesh, int face_count) {
  std::vector<FaceTriangles> faces(static_cast<std::size_t>(face_count));
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    const auto& tri = mesh.triangles[t];
    const double area = 0.5 * (mesh.vertices[tri[1]] - mesh.vertices[tri[0]])
                                  .cross(mesh.vertices[tri[2]] - mesh.vertices[tri[0]])
                                  .norm();
    auto& face = faces[static_cast<std::size_t>(mesh.triangle_faces[t])];
    face.triangles.push_back(t);
    face.cumulative_area.push_back(face.area() + area);
  }
  return faces;
}

// Largest-remainder apportionment of `total` samples to faces by area.
std::vector<int> apportion(const std::vector<FaceTriangles>& faces, int total) {
  double sum = 0.0;
  for (const auto& f : faces) sum += f.area();
  std::vector<int> counts(faces.size(), 0);
  if (!(sum > 0.0) || total <= 0) return counts;
  std::vector<std::pair<double, std::size_t>> remainders;
  int given = 0;
  for (std::size_t i = 0; i < faces.size(); ++i) {
    const double exact = total * faces[i].area() / sum;
    counts[i] = static_cast<int>(std::floor(exact));
    given += counts[i];
    remainders.emplace_back(exact - counts[i], i);
  }
  std::stable_sort(remainders.begin(), remainders.end(),
                   [](const auto& a, const auto& b) { return a.first > b.first; });
  for (int k = 0; k < total - given; ++k) ++counts[remainders[static_cast<std::size_t>(k)].second];
  return counts;
}

// `count` samples on one face: a triangle by area, a uniform barycentric point, its (u, v),
// then the exact surface point and normal there.
void sample_face(const CadShape::Impl& shape, int face_id, const FaceTriangles& face, int count,
                 std::uint32_t seed, PointCloud& out) {
  const CadMesh& mesh = shape.mesh;
  const TopoDS_Face& topo_face = shape.face(face_id);
  const BRepAdaptor_Surface surface(topo_face);
  BRepLProp_SLProps props(surface, 1, 1e-9);
  const double flip = topo_face.Orientation() == TopAbs_REVERSED ? -1.0 : 1.0;
  std::mt19937 rng(seed + 0x9E3779B9u * static_cast<std::uint32_t>(face_id + 1));
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  // A sample that falls where a chord cuts across a curved trim (outside the true face) is
  // drawn again; the attempt cap only guards against a face the classifier rejects entirely.
  for (int s = 0, attempts = 0; s < count && attempts < 20 * count + 100; ++attempts) {
    const double pick = unit(rng) * face.area();
    const auto it =
        std::lower_bound(face.cumulative_area.begin(), face.cumulative_area.end(), pick);
    const auto slot = static_cast<std::size_t>(std::min<std::ptrdiff_t>(
        it - face.cumulative_area.begin(), static_cast<std::ptrdiff_t>(face.triangles.size()) - 1));
    const std::size_t triangle = face.triangles[slot];
    const auto& tri = mesh.triangles[triangle];
    // Uniform point in a triangle: (1 - sqrt(r1), sqrt(r1) (1 - r2), sqrt(r1) r2).
    const double r1 = std::sqrt(unit(rng)), r2 = unit(rng);
    const double a = 1.0 - r1, b = r1 * (1.0 - r2), c = r1 * r2;
    const Eigen::Vector2d uv = a * mesh.uv[tri[0]] + b * mesh.uv[tri[1]] + c * mesh.uv[tri[2]];
    if (!inside_trimmed(shape, face_id, static_cast<int>(triangle), uv)) continue;
    ++s;
    const Vec3 chord_normal = (mesh.vertices[tri[1]] - mesh.vertices[tri[0]])
                                  .cross(mesh.vertices[tri[2]] - mesh.vertices[tri[0]])
                                  .normalized();
    props.SetParameters(uv.x(), uv.y());
    const gp_Pnt p = props.Value();
    Vec3 normal = chord_normal;
    if (props.IsNormalDefined()) {
      const gp_Dir& n = props.Normal();
      normal = flip * Vec3(n.X(), n.Y(), n.Z());
    }
    out.points.emplace_back(p.X(), p.Y(), p.Z());
    out.normals.push_back(normal);
    out.face_ids.push_back(face_id);
  }
}

}  // namespace

Expected<PointCloud> sample_cad(const CadShape& shape, const CadSamplingSettings& settings) {
  if (shape.empty()) return fail("sample_cad: the CAD shape is empty");
  if (settings.sample_count < 0)
    return fail("sample_cad: sample_count must be >= 0, got " +
                std::to_string(settings.sample_count));
  const auto faces = group_by_face(shape.mesh(), shape.face_count());
  const auto counts = apportion(faces, settings.sample_count);
  PointCloud cloud;
  cloud.points.reserve(static_cast<std::size_t>(settings.sample_count));
  cloud.normals.reserve(static_cast<std::size_t>(settings.sample_count));
  cloud.face_ids.reserve(static_cast<std::size_t>(settings.sample_count));
  try {
    for (std::size_t f = 0; f < faces.size(); ++f) {
      if (counts[f] == 0) continue;
      sample_face(shape.impl(), static_cast<int>(f), faces[f], counts[f], settings.seed, cloud);
    }
  } catch (const Standard_Failure& e) {
    return fail(describe_occt_failure(shape.report().file + ": sampling", e.GetMessageString()));
  }
  return cloud;
}

}  // namespace springscan::analysis
