#include "analysis/messages/springback_proto.hpp"

#include <gtest/gtest.h>

#include "analysis/messages/verdict_proto.hpp"
#include "simulators/parts/sheet_part.hpp"

namespace springscan::analysis {
using namespace springscan::parts;  // test and demo parts (simulators/parts)
namespace {

TEST(SpringbackProto, ReportHoldsTheBendTableAndSegments) {
  const ProfileSpec spec = z_profile(30, 40, 80, 3);
  const auto model = profile_part_model(spec, {.sample_count = 10000});
  ASSERT_TRUE(model.ok());
  ScanSimulationSettings st;
  st.point_count = 20000;
  const auto scan = simulate_scan(spec, {1.0, 0.2}, st);
  ASSERT_TRUE(scan.ok());
  const auto result = measure_springback(*model, *scan);
  ASSERT_TRUE(result.ok());
  v1::InspectionReport report;
  fill_springback_report(*result, report);
  // The per-bend pass is the verdict's, copied into the report (verdict_proto.hpp).
  EXPECT_FALSE(report.bends(1).pass());
  to_proto(decide_verdict({.bends = result->bends}, {.angle_tolerance_deg = 0.5}), &report);
  ASSERT_EQ(report.segments_size(), 3);
  ASSERT_EQ(report.bends_size(), 2);
  EXPECT_EQ(report.segments(1).kind(), "flange");
  EXPECT_EQ(report.segments(1).cad_faces(0), 2);
  EXPECT_EQ(report.segments(1).local_fit().transform_size(), 16);
  EXPECT_EQ(report.segments(1).local_fit().transform(15), 1.0);
  EXPECT_GT(report.segments(1).points(), 1000);
  const v1::Bend& b0 = report.bends(0);
  EXPECT_NEAR(b0.springback_deg(), 1.0, 0.05);
  EXPECT_NEAR(b0.measured_angle_deg(), 79.0, 0.05);
  EXPECT_DOUBLE_EQ(b0.nominal_angle_deg(), 80.0);
  EXPECT_FALSE(b0.pass());  // 1 deg of springback against 0.5 deg tolerance
  EXPECT_TRUE(report.bends(1).pass());
  EXPECT_DOUBLE_EQ(b0.angle_tolerance_deg(), 0.5);
  EXPECT_TRUE(b0.measured());
  EXPECT_EQ(b0.segment_a(), 0);
  EXPECT_EQ(b0.segment_b(), 1);
  EXPECT_EQ(b0.cad_faces(0), 1);
  EXPECT_NEAR(std::abs(b0.axis_direction().y()), 1.0, 1e-12);
}

}  // namespace
}  // namespace springscan::analysis
