#include "simulators/parts/sheet_part.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

namespace springscan::analysis {
using namespace springscan::parts;  // test and demo parts (simulators/parts)
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

TEST(SheetPart, SamplesLieOnTheSurfaceWithTheirFaceAndNormal) {
  const ProfileSpec spec = hat_profile(20, 30, 40, 100, 4);
  const auto model = profile_part_model(spec, {.sample_count = 5000});
  ASSERT_TRUE(model.ok()) << model.message();
  EXPECT_NEAR(static_cast<double>(model->samples.size()), 5000.0, 500.0);
  EXPECT_EQ(model->face_count, 9);
  for (std::size_t i = 0; i < model->samples.size(); i += 7) {
    const SurfaceHit hit = model->distance->closest(model->samples.points[i]);
    EXPECT_NEAR(hit.signed_distance_mm, 0.0, 1e-9);
    EXPECT_NEAR((hit.normal - model->samples.normals[i]).norm(), 0.0, 1e-9);
  }
}

TEST(SheetPart, DistanceHasKnownAnswersOnLineAndArc) {
  // L: 40 mm along +x, left turn of 90 deg with radius 3 about (40, 3), then 30 mm up.
  const auto distance = profile_surface_distance(l_profile(40, 30, 90, 3));
  const SurfaceHit above = distance->closest({10, 5, 2});
  EXPECT_NEAR(above.signed_distance_mm, 2.0, 1e-12);
  EXPECT_EQ(above.face_id, 0);
  EXPECT_TRUE(above.normal.isApprox(Vec3::UnitZ()));
  const SurfaceHit below = distance->closest({10, 5, -1.5});
  EXPECT_NEAR(below.signed_distance_mm, -1.5, 1e-12);
  // Halfway round the arc, 1 mm towards its centre (the reference side faces the centre).
  const Vec3 on_arc(40 + 3 * std::sin(45 * kDeg), 7, 3 - 3 * std::cos(45 * kDeg));
  const Vec3 inward = (Vec3(40, 7, 3) - on_arc).normalized();
  const SurfaceHit arc = distance->closest(on_arc + inward);
  EXPECT_EQ(arc.face_id, 1);
  EXPECT_NEAR(arc.signed_distance_mm, 1.0, 1e-12);
  EXPECT_NEAR((arc.foot - on_arc).norm(), 0.0, 1e-12);
  // Beyond the sheet's edge in y: the foot is clamped to the edge.
  EXPECT_NEAR(distance->closest({10, 70, 0}).signed_distance_mm, 10.0, 1e-12);
}

TEST(SheetPart, DistanceMatchesBruteForceOverDenseSamples) {
  const ProfileSpec spec = z_profile(30, 40, 60, 5);
  const auto dense = profile_part_model(spec, {.sample_count = 200000});
  ASSERT_TRUE(dense.ok());
  std::mt19937 rng(4);
  std::uniform_real_distribution<double> ux(-5, 70), uy(-5, 65), uz(-10, 50);
  for (int q = 0; q < 50; ++q) {
    const Vec3 p(ux(rng), uy(rng), uz(rng));
    double best = 1e300;
    for (const Vec3& s : dense->samples.points) best = std::min(best, (s - p).norm());
    // The grid spacing is about 0.16 mm, so brute force overestimates by at most ~0.12 mm.
    EXPECT_NEAR(std::abs(dense->distance->closest(p).signed_distance_mm), best, 0.12);
  }
}

TEST(SheetPart, SegmentationTurnsFlangeAIntoFlangeB) {
  const ProfileSpec spec = hat_profile(20, 30, 40, 75, 4);
  const auto model = profile_part_model(spec, {.sample_count = 2000});
  ASSERT_TRUE(model.ok());
  const auto& seg = model->segmentation;
  ASSERT_EQ(seg.flanges.size(), 5u);
  ASSERT_EQ(seg.bends.size(), 4u);
  for (const Bend& bend : seg.bends) {
    EXPECT_DOUBLE_EQ(bend.nominal_angle_deg, 75.0);
    const Vec3 turned = Eigen::AngleAxisd(bend.nominal_angle_deg * kDeg, bend.axis_direction) *
                        seg.flanges[static_cast<std::size_t>(bend.flange_a)].normal;
    EXPECT_NEAR((turned - seg.flanges[static_cast<std::size_t>(bend.flange_b)].normal).norm(), 0.0,
                1e-12);
    // The flanges' lines touch the arc, whose axis is `radius` away from both planes.
    for (int f : {bend.flange_a, bend.flange_b}) {
      const Flange& flange = seg.flanges[static_cast<std::size_t>(f)];
      EXPECT_NEAR(std::abs((bend.axis_point - flange.point).dot(flange.normal)), 4.0, 1e-12);
    }
  }
}

TEST(SheetPart, ProducedProfileReducesEachAngleKeepingItsSign) {
  const auto produced = produced_profile(z_profile(30, 40, 90, 3), {2.0, -1.0});
  ASSERT_TRUE(produced.ok());
  EXPECT_DOUBLE_EQ(produced->bend_angles_deg[0], 88.0);
  EXPECT_DOUBLE_EQ(produced->bend_angles_deg[1], -91.0);
  EXPECT_FALSE(produced_profile(z_profile(30, 40, 90, 3), {2.0}).ok());
  EXPECT_FALSE(produced_profile(l_profile(30, 40, 90, 3), {95.0}).ok());
}

TEST(SheetPart, SimulatedScanHasTheNoisePoseAndHolesAsked) {
  const ProfileSpec nominal = u_profile(30, 50, 90, 4);
  const std::vector<double> springback = {1.5, 2.5};
  ScanSimulationSettings st;
  st.point_count = 20000;
  st.noise_sigma_mm = 0.05;
  st.missing_fraction = 0.1;
  st.T_scan_part =
      Eigen::Translation3d(100, -20, 5) * Eigen::AngleAxisd(0.7, Vec3(1, 2, 3).normalized());
  const auto scan = simulate_scan(nominal, springback, st);
  ASSERT_TRUE(scan.ok()) << scan.message();
  ASSERT_EQ(scan->size(), 20000u);
  const auto produced_distance = profile_surface_distance(*produced_profile(nominal, springback));
  double sum_sq = 0.0;
  for (const Vec3& p : scan->points)
    sum_sq +=
        std::pow(produced_distance->closest(st.T_scan_part.inverse() * p).signed_distance_mm, 2);
  EXPECT_NEAR(std::sqrt(sum_sq / 20000.0), 0.05, 0.002);
  // Flange 0 is where the nominal part has it: no springback moves it.
  const auto nominal_distance = profile_surface_distance(nominal);
  int on_flange0 = 0;
  for (const Vec3& p : scan->points) {
    const Vec3 in_part = st.T_scan_part.inverse() * p;
    if (produced_distance->closest(in_part).face_id != 0) continue;
    ++on_flange0;
    EXPECT_LT(std::abs(nominal_distance->closest(in_part).signed_distance_mm), 0.4);
  }
  EXPECT_GT(on_flange0, 1000);
  // The same seed gives the same scan; another seed does not.
  EXPECT_EQ(simulate_scan(nominal, springback, st)->points, scan->points);
  st.seed = 2;
  EXPECT_NE(simulate_scan(nominal, springback, st)->points, scan->points);
}

TEST(SheetPart, OutliersHaveTheirShare) {
  ScanSimulationSettings st;
  st.point_count = 20000;
  st.noise_sigma_mm = 0.0;
  st.outlier_fraction = 0.05;
  const ProfileSpec spec = l_profile(40, 40, 90, 3);
  const auto scan = simulate_scan(spec, {0.0}, st);
  ASSERT_TRUE(scan.ok());
  const auto distance = profile_surface_distance(spec);
  int far = 0;
  for (const Vec3& p : scan->points)
    far += std::abs(distance->closest(p).signed_distance_mm) > 1e-9;
  EXPECT_NEAR(far / 20000.0, 0.05, 0.006);
}

TEST(SheetPart, RejectsBadInputWithTheValue) {
  EXPECT_FALSE(profile_part_model(ProfileSpec{}).ok());
  const auto zero = profile_part_model(l_profile(10, 10, 90, 2), {.sample_count = 0});
  ASSERT_FALSE(zero.ok());
  EXPECT_NE(zero.message().find("sample_count 0"), std::string::npos);
  ScanSimulationSettings st;
  st.missing_fraction = 0.95;
  const auto bad = simulate_scan(l_profile(10, 10, 90, 2), {0.0}, st);
  ASSERT_FALSE(bad.ok());
  EXPECT_NE(bad.message().find("missing_fraction"), std::string::npos);
  // Tiny: one sample per element still describes the part.
  const auto tiny = profile_part_model(l_profile(10, 10, 90, 2), {.sample_count = 1});
  ASSERT_TRUE(tiny.ok());
  EXPECT_GE(tiny->samples.size(), 3u);  // at least one per element
  EXPECT_LE(tiny->samples.size(), 10u);
}

}  // namespace
}  // namespace springscan::analysis
