// Mesh decimation (analysis/preprocess/decimation.hpp): reduction, the contour kept, the error
// bound against the original surface, attributes carried, and the meshes it refuses.
#include "analysis/preprocess/decimation.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <random>
#include <set>
#include <utility>

#include "analysis/core/triangle_bvh.hpp"
#include "simulators/parts/sheet_part.hpp"
#include "tests/analysis/grid_mesh.hpp"
#include "tests/analysis/profile_sampling.hpp"

namespace springscan::analysis {
namespace {

using testing::grid_triangles;

// A rows x columns grid, spacing h, lifted to z = height(x, y).
template <typename Height>
TriangleMesh grid_mesh(std::size_t rows, std::size_t columns, double h, Height height) {
  TriangleMesh mesh;
  for (std::size_t r = 0; r < rows; ++r)
    for (std::size_t c = 0; c < columns; ++c) {
      const double x = h * static_cast<double>(c), y = h * static_cast<double>(r);
      mesh.vertices.emplace_back(x, y, height(x, y));
    }
  mesh.triangles = grid_triangles(rows, columns);
  return mesh;
}

// A scanner's triangulation of an L profile (a 90 degree bend of radius 3 mm): the profile
// sampled on a grid (path x width, spacing 0.5 mm), each grid cell two triangles, with noise
// of `sigma_mm` along z.
ProfileSpec bent_sheet_spec() {
  ProfileSpec spec = l_profile(30, 20, 90, 3);
  spec.width_mm = 15.0;
  return spec;
}

TriangleMesh bent_sheet(double sigma_mm, std::uint64_t seed) {
  const testing::ProfileSamples grid = testing::sample_profile_spacing(bent_sheet_spec(), 0.5);
  TriangleMesh mesh;
  mesh.vertices = grid.points;
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, sigma_mm);
  if (sigma_mm > 0.0)
    for (Vec3& p : mesh.vertices) p.z() += noise(rng);
  const std::size_t columns = static_cast<std::size_t>(grid.last_step) + 1;
  mesh.triangles = grid_triangles(mesh.vertices.size() / columns, columns);
  return mesh;
}

// Vertices on an edge that only one triangle has: the contour, computed here by brute force.
std::set<std::uint32_t> boundary_vertices(const TriangleMesh& mesh) {
  std::map<std::pair<std::uint32_t, std::uint32_t>, int> uses;
  for (const auto& t : mesh.triangles)
    for (int e = 0; e < 3; ++e) {
      const std::uint32_t a = t[e], b = t[(e + 1) % 3];
      ++uses[{std::min(a, b), std::max(a, b)}];
    }
  std::set<std::uint32_t> out;
  for (const auto& [edge, count] : uses)
    if (count == 1) out.insert({edge.first, edge.second});
  return out;
}

// The distance of p to the nearest triangle of `mesh`, by trying every triangle.
double brute_force_distance(const Vec3& p, const TriangleMesh& mesh) {
  double best = std::numeric_limits<double>::infinity();
  for (const auto& t : mesh.triangles) {
    const auto foot =
        closest_on_triangle(p, mesh.vertices[t[0]], mesh.vertices[t[1]], mesh.vertices[t[2]]);
    best = std::min(best, foot.squared_distance);
  }
  return std::sqrt(best);
}

TEST(Decimation, PlaneShrinksToFewTrianglesAndKeepsItsContour) {
  const TriangleMesh plane = grid_mesh(40, 50, 1.0, [](double, double) { return 0.0; });
  const auto result = decimate_mesh(plane);
  ASSERT_TRUE(result.ok()) << result.message();
  EXPECT_GE(result->achieved_reduction, 0.85);
  EXPECT_EQ(result->input_triangles, plane.triangles.size());
  const std::set<std::uint32_t> kept(result->kept.begin(), result->kept.end());
  for (std::uint32_t v : boundary_vertices(plane)) EXPECT_TRUE(kept.count(v)) << "vertex " << v;
  EXPECT_LT(result->max_deviation_mm, 1e-9);
}

// Noise-free, the criterion bounds both ways: every scanned point is within max_error_mm of the
// reduced mesh, and the reduced mesh (its triangles' centroids and edge midpoints) within about
// max_error_mm of the true surface: the criterion is checked at the deleted vertices, and a
// chord between them sags a little more (up to 14 % over, measured).
TEST(Decimation, ReducedSurfaceStaysWithinTheMaxErrorOfTheOriginalSurface) {
  const TriangleMesh bent = bent_sheet(0.0, 1);
  const auto truth = profile_surface_distance(bent_sheet_spec());
  for (double max_error_mm : {0.05, 0.01}) {
    DecimationSettings settings;
    settings.max_error_mm = max_error_mm;
    const auto result = decimate_mesh(bent, settings);
    ASSERT_TRUE(result.ok()) << result.message();
    EXPECT_GT(result->achieved_reduction, 0.5) << max_error_mm;
    double worst = 0.0;
    for (const Vec3& p : bent.vertices)
      worst = std::max(worst, brute_force_distance(p, result->mesh));
    EXPECT_LE(worst, max_error_mm);
    EXPECT_NEAR(result->max_deviation_mm, worst, 1e-9);  // the stage's own figure is this one
    const auto& v = result->mesh.vertices;
    double sag = 0.0;
    for (const auto& t : result->mesh.triangles) {
      for (const Vec3& p :
           {Vec3((v[t[0]] + v[t[1]] + v[t[2]]) / 3.0), Vec3((v[t[0]] + v[t[1]]) / 2),
            Vec3((v[t[1]] + v[t[2]]) / 2), Vec3((v[t[2]] + v[t[0]]) / 2)})
        sag = std::max(sag, std::abs(truth->closest(p).signed_distance_mm));
    }
    EXPECT_LE(sag, 1.2 * max_error_mm);
    std::printf("max error %.3f mm: deleted vertices within %.4f mm, surface within %.4f mm\n",
                max_error_mm, worst, sag);
    // Vertices are not moved: each output vertex is its input vertex, bit for bit.
    for (std::size_t i = 0; i < result->kept.size(); ++i)
      EXPECT_EQ(result->mesh.vertices[i], bent.vertices[result->kept[i]]);
  }
}

// On a noisy scan the re-triangulation joins noisy neighbours, so the scanned points may lie a
// few sigmas beyond the criterion; the stage measures it.
TEST(Decimation, NoisyScanDeviationIsMeasured) {
  constexpr double kSigma = 0.005;
  const TriangleMesh bent = bent_sheet(kSigma, 7);
  DecimationSettings settings;
  settings.max_error_mm = 0.03;
  const auto result = decimate_mesh(bent, settings);
  ASSERT_TRUE(result.ok()) << result.message();
  EXPECT_GT(result->achieved_reduction, 0.5);
  double worst = 0.0;
  for (const Vec3& p : bent.vertices)
    worst = std::max(worst, brute_force_distance(p, result->mesh));
  EXPECT_NEAR(result->max_deviation_mm, worst, 1e-9);
  EXPECT_LE(worst, settings.max_error_mm + 6 * kSigma);
}

TEST(Decimation, TighterErrorKeepsMoreVertices) {
  const TriangleMesh bent = bent_sheet(0.0, 1);
  DecimationSettings loose, tight;
  loose.max_error_mm = 0.05;
  tight.max_error_mm = 0.001;
  const auto a = decimate_mesh(bent, loose), b = decimate_mesh(bent, tight);
  ASSERT_TRUE(a.ok() && b.ok());
  EXPECT_LT(a->mesh.vertices.size(), b->mesh.vertices.size());
  EXPECT_LE(b->max_deviation_mm, 0.001);
}

TEST(Decimation, BoundaryVertexDeletionIsASetting) {
  const TriangleMesh plane = grid_mesh(20, 20, 1.0, [](double, double) { return 0.0; });
  DecimationSettings settings;
  settings.boundary_vertex_deletion = true;
  const auto result = decimate_mesh(plane, settings);
  ASSERT_TRUE(result.ok()) << result.message();
  const std::set<std::uint32_t> kept(result->kept.begin(), result->kept.end());
  std::size_t boundary_kept = 0;
  const auto boundary = boundary_vertices(plane);
  for (std::uint32_t v : boundary) boundary_kept += kept.count(v);
  EXPECT_LT(boundary_kept, boundary.size());
}

TEST(Decimation, OneTriangleAndIsolatedVerticesPassThrough) {
  TriangleMesh mesh;
  mesh.vertices = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(5, 5, 5)};
  mesh.triangles = {{0, 1, 2}};
  const auto result = decimate_mesh(mesh);
  ASSERT_TRUE(result.ok()) << result.message();
  EXPECT_EQ(result->mesh.triangles.size(), 1u);
  EXPECT_EQ(result->isolated_vertices, 1u);
  std::vector<std::uint32_t> kept = result->kept;
  std::sort(kept.begin(), kept.end());
  EXPECT_EQ(kept, (std::vector<std::uint32_t>{0, 1, 2, 3}));
}

TEST(Decimation, ScanKeepsTheAttributesOfItsVertices) {
  const TriangleMesh plane = grid_mesh(10, 10, 1.0, [](double, double) { return 0.0; });
  PointCloud cloud;
  cloud.points = plane.vertices;
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    cloud.normals.push_back(Vec3::UnitZ());
    cloud.scalars.push_back(static_cast<double>(i));
  }
  const auto scan = decimate_scan(cloud, plane.triangles);
  ASSERT_TRUE(scan.ok()) << scan.message();
  ASSERT_EQ(scan->cloud.size(), scan->result.kept.size());
  ASSERT_EQ(scan->cloud.scalars.size(), scan->cloud.size());
  for (std::size_t i = 0; i < scan->cloud.size(); ++i) {
    EXPECT_EQ(scan->cloud.points[i], cloud.points[scan->result.kept[i]]);
    EXPECT_EQ(scan->cloud.scalars[i], static_cast<double>(scan->result.kept[i]));
  }
}

TEST(Decimation, BadMeshesAreRefusedByName) {
  TriangleMesh mesh;
  mesh.vertices = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)};
  const auto expect_error = [](const TriangleMesh& m, const std::string& needle) {
    const auto result = decimate_mesh(m);
    ASSERT_FALSE(result.ok());
    EXPECT_EQ(result.code(), ErrorCode::kInvalidInput);
    EXPECT_NE(result.message().find(needle), std::string::npos) << result.message();
  };
  expect_error(mesh, "no triangles");
  mesh.triangles = {{0, 1, 7}};
  expect_error(mesh, "triangle 0 names vertex 7, past the 3 vertices");
  mesh.triangles = {{0, 1, 1}};
  expect_error(mesh, "names vertex 1 twice");
  mesh.triangles = {{0, 1, 2}};
  mesh.vertices[2].y() = std::numeric_limits<double>::quiet_NaN();
  expect_error(mesh, "vertex 2 is not finite");
  mesh.vertices[2] = Vec3(0, 3e36, 0);  // a float STL's garbage corner
  expect_error(mesh, "vertex 2 lies");
  mesh.vertices[2] = Vec3(0, 1, 0);
  mesh.triangles = {{0, 1, 2}, {1, 0, 2}};  // back to back
  expect_error(mesh, "triangles 0 and 1 have the same three vertices");
  mesh.vertices.emplace_back(1, 1, 0);
  mesh.triangles = {{0, 1, 2}, {1, 2, 3}};  // wound against each other across edge 1-2
  expect_error(mesh, "triangles 0 and 1 both run edge 1-2 the same way");
  expect_error(TriangleMesh{}, "no triangles");
  // A stray corner 1e6 mm out on a 1 mm grid: vtkDecimatePro's tolerance (1e-5 of the box)
  // would exceed the grid's edges, and it read vertex -1 on such input (found by fuzzing).
  TriangleMesh spiked = grid_mesh(5, 5, 1.0, [](double, double) { return 0.0; });
  spiked.vertices[7].z() = 1e6;
  expect_error(spiked, "more than 10^4 times their median edge");
  for (Vec3& v : spiked.vertices) v.z() = 0.0;  // every edge zero length: nothing to resolve
  for (Vec3& v : spiked.vertices) v.x() = v.y() = 0.0;
  expect_error(spiked, "median edge (0.000000 mm)");
}

// A far point in no triangle (a stray scanner return) passes through and does not reach VTK,
// whose tolerance would otherwise grow with it (it derives it from all the points it is given).
TEST(Decimation, FarIsolatedVertexPassesThroughAndDoesNotChangeTheResult) {
  const TriangleMesh plane =
      grid_mesh(20, 20, 1.0, [](double x, double y) { return 0.01 * std::sin(x) * std::cos(y); });
  TriangleMesh with_stray = plane;
  with_stray.vertices.emplace_back(0.0, 0.0, 4e5);
  const auto base = decimate_mesh(plane);
  const auto stray = decimate_mesh(with_stray);
  ASSERT_TRUE(base.ok()) << base.message();
  ASSERT_TRUE(stray.ok()) << stray.message();
  EXPECT_EQ(stray->isolated_vertices, 1u);
  EXPECT_EQ(stray->mesh.triangles, base->mesh.triangles);
  ASSERT_EQ(stray->kept.size(), base->kept.size() + 1);
  EXPECT_EQ(stray->kept.back(), plane.vertices.size());
  EXPECT_EQ(stray->mesh.vertices.back(), with_stray.vertices.back());
}

TEST(Decimation, SettingsOutOfRangeNameTheField) {
  const TriangleMesh plane = grid_mesh(3, 3, 1.0, [](double, double) { return 0.0; });
  DecimationSettings s;
  s.target_reduction = 1.0;
  auto result = decimate_mesh(plane, s);
  ASSERT_FALSE(result.ok());
  EXPECT_EQ(result.code(), ErrorCode::kInvalidSettings);
  EXPECT_NE(result.message().find("mesh_decimation.target_reduction"), std::string::npos);
  s = {};
  s.max_error_mm = 0.0;
  EXPECT_NE(validate(s).message().find("max_error_mm"), std::string::npos);
  s = {};
  s.feature_angle_deg = std::numeric_limits<double>::infinity();
  EXPECT_NE(validate(s).message().find("feature_angle_deg"), std::string::npos);
  EXPECT_TRUE(validate(DecimationSettings{}).ok());
}

}  // namespace
}  // namespace springscan::analysis
