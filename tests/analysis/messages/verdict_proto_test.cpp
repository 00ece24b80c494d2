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

// Every decision and the rule that made them reach the report: the part's, the surface's with
// the U it was judged with, each bend's and each flange's (matched by id).
TEST(VerdictProto, DecisionsAndTheRuleAreCopiedIntoTheReport) {
  VerdictResult verdict;
  verdict.decision = PartDecision::kUndecided;
  verdict.decision_rule = DecisionRule::kGuardBand;
  verdict.surface_decision = Conformity::kConforming;
  verdict.surface_uncertainty_mm = 0.04;
  verdict.bends = {{.bend_id = 2, .decision = Conformity::kUndecided},
                   {.bend_id = 3, .pass = true, .decision = Conformity::kConforming},
                   {.bend_id = 5, .pass = true}};  // a closed hem: not judged
  verdict.flanges = {{.flange_id = 1, .shape_decision = Conformity::kNonconforming}};
  v1::InspectionReport report;
  for (const int id : {5, 3, 2}) report.add_bends()->set_id(id);
  for (const int id : {0, 1}) report.add_segments()->set_id(id);
  to_proto(verdict, &report);
  EXPECT_FALSE(report.verdict().pass());
  EXPECT_EQ(report.verdict().decision(), v1::Verdict::UNDECIDED);
  EXPECT_EQ(report.verdict().decision_rule(), v1::VerdictSettings::GUARD_BAND);
  EXPECT_EQ(report.deviation().decision(), v1::CONFORMING);
  EXPECT_EQ(report.deviation().uncertainty_mm(), 0.04);
  EXPECT_EQ(report.bends(0).decision(), v1::CONFORMITY_UNSPECIFIED);
  EXPECT_EQ(report.bends(1).decision(), v1::CONFORMING);
  EXPECT_EQ(report.bends(2).decision(), v1::UNDECIDED);
  EXPECT_EQ(report.segments(0).shape_decision(), v1::CONFORMITY_UNSPECIFIED);
  EXPECT_EQ(report.segments(1).shape_decision(), v1::NONCONFORMING);
  verdict.decision = PartDecision::kPass;
  verdict.pass = true;
  verdict.decision_rule = DecisionRule::kSimple;
  to_proto(verdict, &report);
  EXPECT_TRUE(report.verdict().pass());
  EXPECT_EQ(report.verdict().decision(), v1::Verdict::PASS);
  EXPECT_EQ(report.verdict().decision_rule(), v1::VerdictSettings::SIMPLE);
  verdict.decision = PartDecision::kFail;
  to_proto(verdict, &report);
  EXPECT_EQ(report.verdict().decision(), v1::Verdict::FAIL);
}

TEST(VerdictProto, TheDecisionRuleIsReadWithGuardBandByDefault) {
  v1::VerdictSettings m;
  auto s = from_proto(m);
  ASSERT_TRUE(s) << s.message();
  EXPECT_EQ(s->decision_rule, DecisionRule::kGuardBand);
  m.set_decision_rule(v1::VerdictSettings::SIMPLE);
  s = from_proto(m);
  ASSERT_TRUE(s) << s.message();
  EXPECT_EQ(s->decision_rule, DecisionRule::kSimple);
  m.set_decision_rule(v1::VerdictSettings::DECISION_RULE_UNSPECIFIED);
  EXPECT_EQ(from_proto(m)->decision_rule, DecisionRule::kGuardBand);
  v1::VerdictSettings out;
  to_proto(VerdictSettings{.decision_rule = DecisionRule::kSimple}, &out);
  EXPECT_EQ(out.decision_rule(), v1::VerdictSettings::SIMPLE);
  to_proto(VerdictSettings{}, &out);
  EXPECT_EQ(out.decision_rule(), v1::VerdictSettings::GUARD_BAND);
}

}  // namespace
}  // namespace springscan::analysis
