// The springback stage inside run_inspection: a whole inspection of a simulated bent part.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "analysis/inspection/pipeline.hpp"
#include "simulators/parts/shaped_profile.hpp"
#include "simulators/parts/sheet_part.hpp"

namespace springscan::analysis {
using namespace springscan::parts;  // test and demo parts (simulators/parts)
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

TEST(SpringbackPipeline, ReportHoldsTheMeasuredBendTable) {
  // An L with unequal legs (no symmetry for the PCA to confuse), scanned in a far-off pose.
  const ProfileSpec spec = l_profile(70, 35, 95, 3);
  const auto model = profile_part_model(spec, {.sample_count = 20000});
  ASSERT_TRUE(model.ok());
  ScanSimulationSettings st;
  st.point_count = 30000;
  st.noise_sigma_mm = 0.02;
  st.T_scan_part = Eigen::Translation3d(150, -40, 310) *
                   Eigen::AngleAxisd(35 * kDeg, Vec3(1, -2, 0.5).normalized());
  const auto scan = simulate_scan(spec, {1.7}, st);
  ASSERT_TRUE(scan.ok());
  v1::AnalysisSettings settings;
  settings.mutable_verdict()->set_angle_tolerance_deg(2.0);
  settings.mutable_springback()->set_bend_margin_mm(2.5);
  const auto outcome = run_inspection(*model, *scan, settings);
  ASSERT_TRUE(outcome.ok()) << outcome.message();
  const v1::InspectionReport& report = outcome->report;
  ASSERT_EQ(report.bends_size(), 1);
  ASSERT_EQ(report.segments_size(), 2);
  const v1::Bend& bend = report.bends(0);
  EXPECT_TRUE(bend.measured());
  EXPECT_NEAR(bend.springback_deg(), 1.7, 0.05);
  EXPECT_NEAR(bend.measured_angle_deg(), 95.0 - 1.7, 0.05);
  EXPECT_DOUBLE_EQ(bend.angle_tolerance_deg(), 2.0);
  EXPECT_TRUE(bend.pass());
  EXPECT_GT(report.segments(0).points(), 1000);
  EXPECT_GT(report.timings_ms().local_fits(), 0.0);
  EXPECT_DOUBLE_EQ(report.settings().springback().bend_margin_mm(), 2.5);
  EXPECT_GT(report.settings().springback().max_iterations(), 0);
}

TEST(SpringbackPipeline, BadLocalFitSettingsNameTheField) {
  const auto model = profile_part_model(l_profile(40, 30, 90, 3), {.sample_count = 2000});
  ASSERT_TRUE(model.ok());
  const auto scan = simulate_scan(l_profile(40, 30, 90, 3), {0.0}, {});
  ASSERT_TRUE(scan.ok());
  v1::AnalysisSettings settings;
  settings.mutable_springback()->set_max_correspondence_distance_mm(-1.0);
  const auto outcome = run_inspection(*model, *scan, settings);
  ASSERT_FALSE(outcome.ok());
  EXPECT_NE(outcome.message().find("springback.max_correspondence_distance_mm"), std::string::npos);
}

// The shape figures and their verdict rules through a whole inspection: an L whose long leg
// is curled (rho 250 mm) and whose bend opens by 1 deg more at one end than at the other.
TEST(SpringbackPipeline, ShapeFiguresAndTheirRulesReachTheReport) {
  ProfileSpec spec = l_profile(70, 35, 95, 3);
  spec.width_mm = 100;
  ProfileShape shape;
  shape.springback_deg = {1.2};
  shape.springback_gradient_deg_per_100mm = {1.0};
  shape.curl_radius_mm = {250, 0};
  const auto model = profile_part_model(spec, {.sample_count = 20000});
  ASSERT_TRUE(model.ok());
  ScanSimulationSettings st;
  st.point_count = 40000;
  st.T_scan_part = Eigen::Translation3d(150, -40, 310) *
                   Eigen::AngleAxisd(35 * kDeg, Vec3(1, -2, 0.5).normalized());
  const auto scan = simulate_shaped_scan(spec, shape, st);
  ASSERT_TRUE(scan.ok());
  v1::AnalysisSettings settings;
  settings.mutable_verdict()->set_angle_tolerance_deg(2.0);
  settings.mutable_verdict()->set_max_angle_spread_deg(0.5);
  settings.mutable_verdict()->set_min_curl_radius_mm(400);
  settings.mutable_springback()->set_station_spacing_mm(25);
  const auto outcome = run_inspection(*model, *scan, settings);
  ASSERT_TRUE(outcome.ok()) << outcome.message();
  const v1::InspectionReport& report = outcome->report;
  ASSERT_EQ(report.bends_size(), 1);
  const v1::Bend& bend = report.bends(0);
  EXPECT_EQ(bend.angle_along_bend_size(), 4);       // 100 mm at 25 mm
  EXPECT_NEAR(bend.angle_spread_deg(), 0.75, 0.1);  // stations 12.5 .. 87.5 mm
  EXPECT_TRUE(bend.end_tangents());
  EXPECT_NEAR(bend.measured_angle_deg(), shaped_bend_angle_deg(spec, shape, 0, 50.0), 0.05);
  ASSERT_TRUE(report.segments(0).has_curl_radius_mm());
  EXPECT_NEAR(report.segments(0).curl_radius_mm(), 250.0, 7.5);
  EXPECT_FALSE(report.segments(1).has_curl_radius_mm());
  EXPECT_DOUBLE_EQ(report.settings().springback().station_spacing_mm(), 25.0);
  EXPECT_DOUBLE_EQ(report.settings().verdict().min_curl_radius_mm(), 400.0);
  const auto has = [&report](const std::string& text) {
    for (const auto& reason : report.verdict().reasons())
      if (reason.find(text) != std::string::npos) return true;
    return false;
  };
  EXPECT_TRUE(has("bend 0 angle spread along the bend")) << report.verdict().DebugString();
  EXPECT_TRUE(has("flange 0 curl radius")) << report.verdict().DebugString();
  EXPECT_FALSE(has("flange 1")) << report.verdict().DebugString();
}

}  // namespace
}  // namespace springscan::analysis
