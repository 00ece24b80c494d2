// The springback stage inside run_inspection: a whole inspection of a simulated bent part.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "analysis/inspection/pipeline.hpp"
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

}  // namespace
}  // namespace springscan::analysis
