// The verdict's decision goes into the report unchanged: the report and the PLC read the
// per-bend pass the verdict computed, never a second computation.
#include "analysis/messages/verdict_proto.hpp"

#include <gtest/gtest.h>

namespace springscan::analysis {
namespace {

TEST(VerdictProto, TheDecisionIsCopiedIntoTheReport) {
  VerdictResult verdict;
  verdict.pass = false;
  verdict.reasons = {
      "bend 7 springback 2.00 deg (nominal 90.00, measured 88.00) exceeds "
      "tolerance 1.50 deg"};
  verdict.tolerance_mm = 0.3;
  verdict.fraction_out_of_tolerance = 0.125;
  verdict.bends = {{.bend_id = 7, .angle_tolerance_deg = 1.5, .pass = false},
                   {.bend_id = 4, .angle_tolerance_deg = 2.0, .pass = true}};
  v1::InspectionReport report;
  report.add_bends()->set_id(4);  // report order need not be the verdict's
  report.add_bends()->set_id(7);
  report.mutable_bends(1)->set_pass(true);  // whatever was there is replaced
  to_proto(verdict, &report);
  EXPECT_FALSE(report.verdict().pass());
  ASSERT_EQ(report.verdict().reasons_size(), 1);
  EXPECT_EQ(report.verdict().reasons(0), verdict.reasons[0]);
  EXPECT_EQ(report.deviation().tolerance_mm(), 0.3);
  EXPECT_EQ(report.deviation().fraction_out_of_tolerance(), 0.125);
  EXPECT_TRUE(report.bends(0).pass());
  EXPECT_EQ(report.bends(0).angle_tolerance_deg(), 2.0);
  EXPECT_FALSE(report.bends(1).pass());
  EXPECT_EQ(report.bends(1).angle_tolerance_deg(), 1.5);
}

TEST(VerdictProto, SettingsRoundTrip) {
  const VerdictSettings v{.tolerance_mm = 0.3, .angle_tolerance_deg = 0.5, .max_fit_rms_mm = 0.4};
  v1::VerdictSettings m;
  to_proto(v, &m);
  const auto back = from_proto(m);
  ASSERT_TRUE(back) << back.message();
  EXPECT_EQ(back->tolerance_mm, 0.3);
  EXPECT_EQ(back->angle_tolerance_deg, 0.5);
  EXPECT_EQ(back->max_fit_rms_mm, 0.4);
}

}  // namespace
}  // namespace springscan::analysis
