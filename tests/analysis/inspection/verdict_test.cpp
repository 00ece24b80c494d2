// The verdict: each rule fails on its own, with its numbers in the reason.
#include "analysis/inspection/verdict.hpp"

#include <gtest/gtest.h>

#include <limits>
#include <string>

namespace springscan::analysis {
namespace {

// A report that passes every default rule.
v1::InspectionReport good_report() {
  v1::InspectionReport r;
  auto* d = r.mutable_deviation();
  d->set_points(1000);
  d->set_min(-0.31);
  d->set_max(0.42);
  d->set_p95(0.28);
  r.mutable_global_fit()->set_rms_final(0.12);
  r.mutable_global_fit()->set_rms_residual(0.02);
  auto* field = r.mutable_deformation_field();
  field->set_method("min_cost_matching");
  field->set_model_points(594);
  field->set_coverage(1.0);
  for (int id = 0; id < 2; ++id) {
    auto* b = r.add_bends();
    b->set_id(id);
    b->set_measured(true);
    b->set_nominal_angle_deg(90.0);
    b->set_measured_angle_deg(89.6);
    b->set_springback_deg(0.4);
  }
  return r;
}

bool has_reason(const v1::Verdict& v, const std::string& text) {
  for (const auto& reason : v.reasons()) {
    if (reason.find(text) != std::string::npos) return true;
  }
  return false;
}

TEST(Verdict, GoodPartPasses) {
  const auto v = decide_verdict(good_report());
  EXPECT_TRUE(v.pass());
  EXPECT_EQ(v.reasons_size(), 0);
}

TEST(Verdict, SurfaceDeviationByP95OrMax) {
  auto r = good_report();
  r.mutable_deviation()->set_p95(0.84);
  auto v = decide_verdict(r);
  EXPECT_FALSE(v.pass());
  ASSERT_EQ(v.reasons_size(), 1);
  EXPECT_EQ(v.reasons(0), "p95 |deviation| 0.84 mm > tolerance 0.50 mm");

  r = good_report();  // p95 fine, but one point is 0.61 mm off: only MAX sees it
  r.mutable_deviation()->set_min(-0.61);
  EXPECT_TRUE(decide_verdict(r).pass());
  v = decide_verdict(r, {.deviation_statistic = DeviationStatistic::kMax});
  EXPECT_FALSE(v.pass());
  EXPECT_TRUE(has_reason(v, "max |deviation| 0.61 mm > tolerance 0.50 mm"));
  EXPECT_TRUE(
      decide_verdict(r, {.tolerance_mm = 0.7, .deviation_statistic = DeviationStatistic::kMax})
          .pass());

  r = good_report();
  r.mutable_deviation()->set_points(0);
  EXPECT_TRUE(has_reason(decide_verdict(r), "no surface deviation"));
  r = good_report();
  r.mutable_deviation()->set_p95(std::numeric_limits<double>::quiet_NaN());
  EXPECT_FALSE(decide_verdict(r).pass());
}

TEST(Verdict, SpringbackPerBend) {
  auto r = good_report();
  r.mutable_bends(1)->set_springback_deg(-2.31);
  r.mutable_bends(1)->set_measured_angle_deg(92.31);
  auto v = decide_verdict(r);
  ASSERT_EQ(v.reasons_size(), 1);
  EXPECT_EQ(v.reasons(0),
            "bend 1 springback -2.31 deg (nominal 90.00, measured 92.31) exceeds tolerance "
            "1.00 deg");
  EXPECT_TRUE(decide_verdict(r, {.angle_tolerance_deg = 2.5}).pass());
  r.mutable_bends(1)->set_angle_tolerance_deg(3.0);  // a per-bend tolerance wins
  EXPECT_TRUE(decide_verdict(r).pass());

  r = good_report();
  r.mutable_bends(0)->set_measured(false);
  v = decide_verdict(r);
  EXPECT_TRUE(has_reason(v, "bend 0 not measured"));
  EXPECT_TRUE(decide_verdict(r, {.fail_unmeasured_bends = false}).pass());
}

TEST(Verdict, AnalysisHealth) {
  auto r = good_report();
  r.mutable_deformation_field()->set_coverage(0.72);
  r.mutable_global_fit()->set_rms_residual(1.32);
  const auto v = decide_verdict(r);
  EXPECT_FALSE(v.pass());
  ASSERT_EQ(v.reasons_size(), 2);
  EXPECT_EQ(v.reasons(0), "deformation field coverage 0.72 < minimum 0.90 (min_cost_matching)");
  EXPECT_EQ(v.reasons(1),
            "global fit residual rms 1.32 mm > limit 1.00 mm: the analysis cannot be trusted");
  // No field computed: coverage is not judged.
  r = good_report();
  r.mutable_deformation_field()->set_model_points(0);
  r.mutable_deformation_field()->set_coverage(0.0);
  EXPECT_TRUE(decide_verdict(r).pass());
}

// The distance to the nearest model sample grows with the part's area (sparser samples); it
// must not fail a well-fitted part: only the residual to the surface judges the fit.
TEST(Verdict, FitHealthIgnoresTheSampleSpacing) {
  auto r = good_report();
  r.mutable_global_fit()->set_rms_final(1.37);
  r.mutable_global_fit()->set_rms_residual(0.03);
  EXPECT_TRUE(decide_verdict(r).pass());
}

TEST(Verdict, EveryFailingRuleIsListed) {
  auto r = good_report();
  r.mutable_deviation()->set_p95(0.9);
  r.mutable_bends(0)->set_springback_deg(1.5);
  r.mutable_bends(1)->set_measured(false);
  r.mutable_global_fit()->set_rms_residual(2.0);
  r.mutable_deformation_field()->set_coverage(0.5);
  const auto v = decide_verdict(r);
  EXPECT_FALSE(v.pass());
  EXPECT_EQ(v.reasons_size(), 5);
}

}  // namespace
}  // namespace springscan::analysis
