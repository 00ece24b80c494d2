// run_mesh_inspection: a scanner triangulation of a bent part with known springback, measured
// from every vertex and from the vertices the mesh decimation keeps (paper §2).
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

#include "analysis/inspection/pipeline.hpp"
#include "simulators/parts/sheet_part.hpp"
#include "tests/analysis/grid_mesh.hpp"
#include "tests/analysis/profile_sampling.hpp"
#include "tests/analysis/under_sanitizer.hpp"

namespace springscan::analysis {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

using testing::kUnderSanitizer;

struct MeshScan {
  PointCloud cloud;
  std::vector<std::array<std::uint32_t, 3>> triangles;
};

// The produced part (the nominal hat with `springback_deg` per bend) as a laser line scanner
// triangulates it: a grid of lines across the width, `spacing_mm` apart along the path, noise
// of sigma along each vertex's normal, the part in a far-off pose.
MeshScan scan_mesh(const ProfileSpec& nominal, const std::vector<double>& springback_deg,
                   double spacing_mm, double sigma_mm) {
  const auto produced = produced_profile(nominal, springback_deg);
  EXPECT_TRUE(produced.ok()) << produced.message();
  const testing::ProfileSamples grid = testing::sample_profile_spacing(*produced, spacing_mm);
  const std::size_t columns = static_cast<std::size_t>(grid.last_step) + 1;
  MeshScan scan;
  scan.triangles = testing::grid_triangles(grid.points.size() / columns, columns);
  // Vertex normals from the triangles around each vertex (area-weighted).
  std::vector<Vec3> normals(grid.points.size(), Vec3::Zero());
  for (const auto& t : scan.triangles) {
    const Vec3 n =
        (grid.points[t[1]] - grid.points[t[0]]).cross(grid.points[t[2]] - grid.points[t[0]]);
    for (std::uint32_t v : t) normals[v] += n;
  }
  std::mt19937 rng(11);
  std::normal_distribution<double> noise(0.0, sigma_mm);
  const Transform T_scan_part = Eigen::Translation3d(120, -60, 280) *
                                Eigen::AngleAxisd(25 * kDeg, Vec3(1, 2, -1).normalized());
  for (std::size_t i = 0; i < grid.points.size(); ++i)
    scan.cloud.points.push_back(T_scan_part *
                                (grid.points[i] + noise(rng) * normals[i].normalized()));
  return scan;
}

TEST(PipelineMesh, DecimatedMeshMeasuresTheBendsOfTheFullScan) {
  // A hat with unequal brims: a symmetric part could be fitted end for end (a pose the
  // surface cannot tell apart), which would swap the bends' springbacks.
  ProfileSpec nominal = hat_profile(25, 30, 40, 90, 3);
  nominal.flange_lengths_mm.back() = 35;
  const std::vector<double> springback = {1.2, 0.7, 1.6, 0.4};
  const auto model = profile_part_model(nominal, {.sample_count = 20000});
  ASSERT_TRUE(model.ok()) << model.message();
  const MeshScan scan = scan_mesh(nominal, springback, kUnderSanitizer ? 1.0 : 0.5, 0.01);

  v1::AnalysisSettings full_settings;
  full_settings.mutable_verdict()->set_angle_tolerance_deg(2.0);
  const auto full = run_mesh_inspection(*model, scan.cloud, scan.triangles, full_settings);
  ASSERT_TRUE(full.ok()) << full.message();
  EXPECT_FALSE(full->mesh_reduction.decimated);
  EXPECT_EQ(full->report.input().scan_points(), static_cast<std::int64_t>(scan.cloud.size()));

  v1::AnalysisSettings settings = full_settings;
  settings.mutable_reduction()->mutable_mesh_decimation()->set_enabled(true);
  const auto decimated = run_mesh_inspection(*model, scan.cloud, scan.triangles, settings);
  ASSERT_TRUE(decimated.ok()) << decimated.message();
  const MeshScanReduction& r = decimated->mesh_reduction;
  EXPECT_TRUE(r.decimated);
  EXPECT_LT(r.vertices_out, r.vertices_in / 3) << "the decimation should remove most vertices";
  EXPECT_GT(r.max_deviation_mm, 0.0);  // measured (its bounds: decimation_test.cpp)
  EXPECT_EQ(decimated->report.input().scan_points(), static_cast<std::int64_t>(r.vertices_out));
  EXPECT_TRUE(decimated->report.settings().reduction().mesh_decimation().enabled());

  ASSERT_EQ(full->report.bends_size(), 4);
  ASSERT_EQ(decimated->report.bends_size(), 4);
  for (int b = 0; b < 4; ++b) {
    const v1::Bend& a = full->report.bends(b);
    const v1::Bend& d = decimated->report.bends(b);
    ASSERT_TRUE(a.measured() && d.measured()) << "bend " << b;
    EXPECT_NEAR(d.measured_angle_deg(), a.measured_angle_deg(), 0.01) << "bend " << b;
    EXPECT_NEAR(a.springback_deg(), springback[b], 0.05) << "bend " << b;
    EXPECT_NEAR(d.springback_deg(), springback[b], 0.05) << "bend " << b;
  }
  std::printf(
      "mesh scan: %zu vertices -> %zu (%.1f%% triangles removed), max deviation %.4f mm, "
      "%.1f ms\n",
      r.vertices_in, r.vertices_out,
      100.0 * (1.0 - static_cast<double>(r.triangles_out) / r.triangles_in), r.max_deviation_mm,
      r.time_ms);
  for (int b = 0; b < 4; ++b)
    std::printf("bend %d: full %.4f deg, decimated %.4f deg (truth %.4f)\n", b,
                full->report.bends(b).measured_angle_deg(),
                decimated->report.bends(b).measured_angle_deg(), 90.0 - springback[b]);
}

TEST(PipelineMesh, ABadMeshIsRefusedByName) {
  const auto model = profile_part_model(l_profile(40, 30, 90, 3), {.sample_count = 2000});
  ASSERT_TRUE(model.ok());
  PointCloud cloud;
  cloud.points = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)};
  v1::AnalysisSettings settings;
  settings.mutable_reduction()->mutable_mesh_decimation()->set_enabled(true);
  const auto outcome = run_mesh_inspection(*model, cloud, {{0, 1, 5}}, settings);
  ASSERT_FALSE(outcome.ok());
  EXPECT_EQ(outcome.code(), ErrorCode::kInvalidInput);
  EXPECT_NE(outcome.message().find("scan: mesh: triangle 0 names vertex 5"), std::string::npos)
      << outcome.message();
  settings.mutable_reduction()->mutable_mesh_decimation()->set_max_error_mm(-1.0);
  const auto bad = run_mesh_inspection(*model, cloud, {{0, 1, 2}}, settings);
  ASSERT_FALSE(bad.ok());
  EXPECT_EQ(bad.code(), ErrorCode::kInvalidSettings);
  EXPECT_NE(bad.message().find("reduction.mesh_decimation.max_error_mm"), std::string::npos);
}

}  // namespace
}  // namespace springscan::analysis
