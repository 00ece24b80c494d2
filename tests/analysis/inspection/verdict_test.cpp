// The verdict: each rule fails on its own, with its numbers in the reason; it is computed from
// the stage results and decides the per-bend pass.
#include "analysis/inspection/verdict.hpp"

#include <gtest/gtest.h>

#include <limits>
#include <string>

namespace springscan::analysis {
namespace {

// Stage results that pass every default rule.
VerdictInput good_input() {
  VerdictInput in;
  in.deviation.points = 1000;
  in.deviation.min_mm = -0.31;
  in.deviation.max_mm = 0.42;
  in.deviation.p95_mm = 0.28;
  in.fit_rms_residual_mm = 0.02;
  in.field = {.coverage = 1.0, .model_points = 594, .method = "min_cost_matching"};
  for (int id = 0; id < 2; ++id) {
    BendMeasurement b;
    b.bend_id = id;
    b.measured = true;
    b.nominal_angle_deg = 90.0;
    b.measured_angle_deg = 89.6;
    b.springback_deg = 0.4;
    in.bends.push_back(b);
  }
  return in;
}

bool has_reason(const VerdictResult& v, const std::string& text) {
  for (const auto& reason : v.reasons) {
    if (reason.find(text) != std::string::npos) return true;
  }
  return false;
}

TEST(Verdict, GoodPartPasses) {
  const auto v = decide_verdict(good_input());
  EXPECT_TRUE(v.pass);
  EXPECT_EQ(v.decision, PartDecision::kPass);
  EXPECT_EQ(v.decision_rule, DecisionRule::kGuardBand) << "the guard band by default";
  EXPECT_EQ(v.surface_decision, Conformity::kConforming);
  EXPECT_EQ(v.reasons.size(), 0u);
  ASSERT_EQ(v.bends.size(), 2u);
  EXPECT_TRUE(v.bends[0].pass && v.bends[1].pass);
  EXPECT_EQ(v.bends[0].decision, Conformity::kConforming);
  EXPECT_EQ(v.bends[0].spread_decision, Conformity::kNotJudged);
  EXPECT_EQ(v.bends[1].bend_id, 1);
  EXPECT_EQ(v.bends[1].angle_tolerance_deg, 1.0);
}

TEST(Verdict, SurfaceDeviationByP95OrMax) {
  auto in = good_input();
  in.deviation.p95_mm = 0.84;
  auto v = decide_verdict(in);
  EXPECT_FALSE(v.pass);
  ASSERT_EQ(v.reasons.size(), 1u);
  EXPECT_EQ(v.reasons[0], "p95 |deviation| 0.84 mm (U 0.000 mm) > tolerance 0.50 mm");
  EXPECT_EQ(v.decision, PartDecision::kFail);
  EXPECT_EQ(v.surface_decision, Conformity::kNonconforming);

  in = good_input();  // p95 fine, but one point is 0.61 mm off: only MAX sees it
  in.deviation.min_mm = -0.61;
  EXPECT_TRUE(decide_verdict(in).pass);
  v = decide_verdict(in, {.deviation_statistic = DeviationStatistic::kMax});
  EXPECT_FALSE(v.pass);
  EXPECT_TRUE(has_reason(v, "max |deviation| 0.61 mm (U 0.000 mm) > tolerance 0.50 mm"));
  EXPECT_TRUE(
      decide_verdict(in, {.tolerance_mm = 0.7, .deviation_statistic = DeviationStatistic::kMax})
          .pass);

  in = good_input();
  in.deviation.points = 0;
  EXPECT_TRUE(has_reason(decide_verdict(in), "no surface deviation"));
  EXPECT_EQ(decide_verdict(in).decision, PartDecision::kFail);
  in = good_input();
  in.deviation.p95_mm = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(decide_verdict(in).pass);
  EXPECT_EQ(decide_verdict(in).decision, PartDecision::kUndecided) << "cannot be placed";
  EXPECT_EQ(decide_verdict(in, {.decision_rule = DecisionRule::kSimple}).decision,
            PartDecision::kFail)
      << "SIMPLE fails a value it cannot compare, as before";
}

// The share out of tolerance is judged against the verdict's tolerance, the one the report shows.
TEST(Verdict, FractionOutOfToleranceUsesTheVerdictsTolerance) {
  auto in = good_input();
  const std::vector<double> d = {0.1, -0.6, 0.3, 0.55, -0.2, 0.0, 0.7, -0.4};
  in.signed_distance_mm = d;
  auto v = decide_verdict(in);
  EXPECT_EQ(v.tolerance_mm, 0.5);
  EXPECT_DOUBLE_EQ(v.fraction_out_of_tolerance, 3.0 / 8.0);
  v = decide_verdict(in, {.tolerance_mm = 0.35});
  EXPECT_EQ(v.tolerance_mm, 0.35);
  EXPECT_DOUBLE_EQ(v.fraction_out_of_tolerance, 4.0 / 8.0);
  in.signed_distance_mm = {};
  EXPECT_EQ(decide_verdict(in).fraction_out_of_tolerance, 0.0);
}

TEST(Verdict, SpringbackPerBend) {
  auto in = good_input();
  in.bends[1].springback_deg = -2.31;
  in.bends[1].measured_angle_deg = 92.31;
  auto v = decide_verdict(in);
  ASSERT_EQ(v.reasons.size(), 1u);
  EXPECT_EQ(v.reasons[0],
            "bend 1 springback -2.31 deg (U 0.000; nominal 90.00, measured 92.31) exceeds "
            "tolerance 1.00 deg");
  EXPECT_TRUE(v.bends[0].pass);
  EXPECT_FALSE(v.bends[1].pass);
  EXPECT_TRUE(decide_verdict(in, {.angle_tolerance_deg = 2.5}).pass);
  // A per-bend tolerance wins.
  v = decide_verdict(in, {.angle_tolerance_deg_by_bend = {{1, 3.0}}});
  EXPECT_TRUE(v.pass);
  EXPECT_EQ(v.bends[1].angle_tolerance_deg, 3.0);
  EXPECT_EQ(v.bends[0].angle_tolerance_deg, 1.0);
}

// An unmeasured bend is UNDECIDED, under either rule: never a silent pass. It fails the part
// only when the line asks for it (fail_unmeasured_bends); a closed hem is not judged.
TEST(Verdict, AnUnmeasuredBendIsUndecided) {
  auto in = good_input();
  in.bends[0].measured = false;
  in.bends[0].status = "bend 0 not measured: flange 1: 12 points";
  for (const DecisionRule rule : {DecisionRule::kGuardBand, DecisionRule::kSimple}) {
    auto v = decide_verdict(in, {.decision_rule = rule});
    EXPECT_EQ(v.decision, PartDecision::kUndecided) << to_string(rule);
    EXPECT_FALSE(v.pass);
    EXPECT_FALSE(v.bends[0].pass);
    EXPECT_EQ(v.bends[0].decision, Conformity::kUndecided);
    EXPECT_EQ(v.bends[1].decision, Conformity::kConforming);
    ASSERT_EQ(v.reasons.size(), 1u);
    EXPECT_EQ(v.reasons[0], "bend 0 not measured: flange 1: 12 points (undecided)");
    v = decide_verdict(in, {.fail_unmeasured_bends = true, .decision_rule = rule});
    EXPECT_EQ(v.decision, PartDecision::kFail);
    EXPECT_EQ(v.bends[0].decision, Conformity::kUndecided) << "the bend itself is not known";
    EXPECT_TRUE(has_reason(v, "(fails the part: fail_unmeasured_bends)"));
  }
  in = good_input();
  in.bends[0].measured = false;
  in.bends[0].measurable = false;  // a closed hem
  const auto v = decide_verdict(in);
  EXPECT_EQ(v.decision, PartDecision::kPass);
  EXPECT_TRUE(v.bends[0].pass);
  EXPECT_EQ(v.bends[0].decision, Conformity::kNotJudged);
}

TEST(Verdict, AnalysisHealth) {
  auto in = good_input();
  in.field.coverage = 0.72;
  in.fit_rms_residual_mm = 1.32;
  auto v = decide_verdict(in);
  EXPECT_FALSE(v.pass);
  EXPECT_EQ(v.decision, PartDecision::kFail);
  ASSERT_EQ(v.reasons.size(), 2u);
  EXPECT_EQ(v.reasons[0],
            "deformation field coverage 0.72 < minimum 0.90 (min_cost_matching): the part is not "
            "all in the scan (undecided)");
  EXPECT_EQ(v.reasons[1],
            "global fit residual rms 1.32 mm > limit 1.00 mm: the analysis cannot be trusted");
  // Coverage short alone: what the scan shows conforms, the rest is not measured. No evidence
  // against the part, so UNDECIDED, never FAIL (nor PASS).
  in.fit_rms_residual_mm = 0.03;
  v = decide_verdict(in);
  EXPECT_FALSE(v.pass);
  EXPECT_EQ(v.decision, PartDecision::kUndecided);
  EXPECT_EQ(v.reasons.size(), 1u);
  // No field computed: coverage is not judged.
  in = good_input();
  in.field.model_points = 0;
  in.field.coverage = 0.0;
  EXPECT_TRUE(decide_verdict(in).pass);
}

// The distance to the nearest model sample grows with the part's area (sparser samples); it
// must not fail a well-fitted part: only the residual to the surface judges the fit, and
// rms_final is not even an input.
TEST(Verdict, FitHealthIgnoresTheSampleSpacing) {
  auto in = good_input();
  in.fit_rms_residual_mm = 0.03;
  EXPECT_TRUE(decide_verdict(in).pass);
}

TEST(Verdict, EveryFailingRuleIsListed) {
  auto in = good_input();
  in.deviation.p95_mm = 0.9;
  in.bends[0].springback_deg = 1.5;
  in.bends[1].measured = false;
  in.fit_rms_residual_mm = 2.0;
  in.field.coverage = 0.5;
  const auto v = decide_verdict(in);
  EXPECT_FALSE(v.pass);
  EXPECT_EQ(v.reasons.size(), 5u);
}

TEST(Verdict, ShapeRulesAreOffByDefaultAndNameTheirNumbers) {
  VerdictInput in = good_input();
  in.bends[1].stations = {{-20, 89.5, 0.5}, {0, 89.6, 0.4}, {20, 90.3, -0.3}};
  in.bends[1].angle_min_deg = 89.5;
  in.bends[1].angle_max_deg = 90.3;
  in.bends[1].angle_spread_deg = 0.8;
  in.flanges = {{.flange_id = 0,
                 .measured = true,
                 .flatness_mm = 0.09,
                 .curled = false,
                 .curl_radius_mm = 0.0},
                {.flange_id = 1,
                 .measured = true,
                 .flatness_mm = 1.4,
                 .curled = true,
                 .curl_radius_mm = -180.0}};
  EXPECT_TRUE(decide_verdict(in).pass) << "every shape limit is off by default";
  VerdictSettings s;
  s.max_angle_spread_deg = 0.5;
  s.min_curl_radius_mm = 250.0;
  s.max_flatness_mm = 1.0;
  const auto v = decide_verdict(in, s);
  EXPECT_FALSE(v.pass);
  EXPECT_TRUE(
      has_reason(v, "bend 1 angle spread along the bend 0.80 deg (U 0.000; 89.50 to 90.30)"));
  EXPECT_TRUE(has_reason(v, "flange 1 flatness 1.40 mm (U 0.000 mm) exceeds 1.00 mm"));
  EXPECT_TRUE(
      has_reason(v, "flange 1 curl radius -180.00 mm (U 0.000 mm) is tighter than 250.00 mm"));
  ASSERT_EQ(v.flanges.size(), 2u);
  EXPECT_EQ(v.flanges[0].shape_decision, Conformity::kConforming);
  EXPECT_EQ(v.flanges[1].shape_decision, Conformity::kNonconforming);
  EXPECT_EQ(v.bends[1].spread_decision, Conformity::kNonconforming);
  EXPECT_FALSE(has_reason(v, "flange 0"));
  EXPECT_FALSE(has_reason(v, "bend 0 angle spread"));
  EXPECT_TRUE(v.bends[1].pass) << "the bend's own pass is its springback";
  // The trim edges: off by default, then each edge's larger move against the limit.
  in.flanges[0].edges = {{"free", 0.31, -0.52}, {"side", -0.12, 0.2}};
  EXPECT_FALSE(has_reason(decide_verdict(in, s), "free edge"));
  VerdictSettings edge;
  edge.max_edge_deviation_mm = 0.5;
  EXPECT_TRUE(has_reason(decide_verdict(in, edge),
                         "flange 0 free edge off by 0.31 mm in-plane (U 0.000 mm), -0.52 mm across "
                         "(U 0.000 mm; limit 0.50 mm)"));
  EXPECT_FALSE(has_reason(decide_verdict(in, edge), "side edge"));
  edge.max_edge_deviation_mm = 0.6;
  EXPECT_TRUE(decide_verdict(in, edge).pass);
  edge.max_edge_deviation_mm = 0.15;
  EXPECT_TRUE(has_reason(decide_verdict(in, edge),
                         "flange 0 side edge off by -0.12 mm in-plane (U 0.000 mm), 0.20 mm across "
                         "(U 0.000 mm; limit 0.15 mm)"));
  // Within the limits: no reason.
  s.max_angle_spread_deg = 0.9;
  s.min_curl_radius_mm = 150.0;
  s.max_flatness_mm = 1.5;
  EXPECT_TRUE(decide_verdict(in, s).pass);
}

// The guard band per bend: a springback within U of its limit is UNDECIDED, and so is the part
// when nothing fails; a bend far inside its limit still passes with its U. The reason names the
// value, U and the limit.
TEST(Verdict, ABendWithinUOfItsLimitIsUndecided) {
  auto in = good_input();
  in.bends[0].springback_uncertainty_deg = 0.05;  // 0.4 deg: far inside 1.0
  in.bends[1].springback_deg = 0.98;
  in.bends[1].measured_angle_deg = 89.02;
  in.bends[1].springback_uncertainty_deg = 0.1;
  auto v = decide_verdict(in);
  EXPECT_EQ(v.decision, PartDecision::kUndecided);
  EXPECT_FALSE(v.pass) << "pass only for PASS";
  EXPECT_EQ(v.bends[0].decision, Conformity::kConforming);
  EXPECT_TRUE(v.bends[0].pass);
  EXPECT_EQ(v.bends[1].decision, Conformity::kUndecided);
  EXPECT_FALSE(v.bends[1].pass);
  ASSERT_EQ(v.reasons.size(), 1u);
  EXPECT_EQ(v.reasons[0],
            "bend 1 springback 0.98 deg (U 0.100; nominal 90.00, measured 89.02) undecided, "
            "within U of tolerance 1.00 deg");
  // SIMPLE compares the value alone, and the result says which rule decided.
  v = decide_verdict(in, {.decision_rule = DecisionRule::kSimple});
  EXPECT_EQ(v.decision, PartDecision::kPass);
  EXPECT_EQ(v.decision_rule, DecisionRule::kSimple);
  // Out by more than U: FAIL, and a FAIL anywhere outranks an undecided bend.
  in.bends[0].springback_deg = -1.2;
  v = decide_verdict(in);
  EXPECT_EQ(v.decision, PartDecision::kFail);
  EXPECT_EQ(v.bends[0].decision, Conformity::kNonconforming);
  EXPECT_EQ(v.bends[1].decision, Conformity::kUndecided);
  EXPECT_EQ(v.reasons.size(), 2u);
  // Out by less than U: undecided, never a FAIL the scan cannot prove.
  in.bends[0].springback_deg = -1.04;
  EXPECT_EQ(decide_verdict(in).bends[0].decision, Conformity::kUndecided);
  // A health failure fails the part whatever the characteristics say.
  in = good_input();
  in.bends[1].springback_deg = 0.98;
  in.bends[1].springback_uncertainty_deg = 0.1;
  in.orientation_ambiguous = true;
  EXPECT_EQ(decide_verdict(in).decision, PartDecision::kFail);
}

TEST(Verdict, TheSurfaceUsesTheUOfTheStatisticItCompares) {
  auto in = good_input();
  in.deviation.p95_mm = 0.47;
  in.deviation.p95_uncertainty_mm = 0.05;
  in.deviation.max_mm = 0.62;
  in.deviation.max_uncertainty_mm = 0.08;
  auto v = decide_verdict(in);
  EXPECT_EQ(v.surface_decision, Conformity::kUndecided);
  EXPECT_EQ(v.surface_uncertainty_mm, 0.05);
  EXPECT_EQ(v.decision, PartDecision::kUndecided);
  EXPECT_TRUE(
      has_reason(v, "p95 |deviation| 0.47 mm (U 0.050 mm) undecided, within U of tolerance"));
  v = decide_verdict(in, {.deviation_statistic = DeviationStatistic::kMax});
  EXPECT_EQ(v.surface_uncertainty_mm, 0.08);
  EXPECT_EQ(v.surface_decision, Conformity::kNonconforming);  // 0.62 > 0.5 + 0.08
  in.deviation.p95_uncertainty_mm = 0.02;
  EXPECT_EQ(decide_verdict(in).decision, PartDecision::kPass);  // 0.47 <= 0.5 - 0.02
}

// The shape criteria with their own U: flatness and edges against an upper limit, the curl
// radius against a lower one, the angle spread with the U of the two stations that span it.
TEST(Verdict, ShapeCriteriaUseTheirUncertainties) {
  VerdictInput in = good_input();
  in.bends[1].stations = {{-20, 89.5, 0.5, 0.03}, {0, 89.6, 0.4, 0.01}, {20, 90.3, -0.3, 0.04}};
  in.bends[1].angle_min_deg = 89.5;
  in.bends[1].angle_max_deg = 90.3;
  in.bends[1].angle_spread_deg = 0.8;
  in.flanges = {{.flange_id = 0,
                 .measured = true,
                 .flatness_mm = 0.95,
                 .curled = true,
                 .curl_radius_mm = -240.0,
                 .flatness_uncertainty_mm = 0.1,
                 .curl_radius_uncertainty_mm = 30.0,
                 .edges = {{"free", 0.31, -0.52, 0.05}}}};
  VerdictSettings s{.max_angle_spread_deg = 0.78,
                    .min_curl_radius_mm = 250.0,
                    .max_flatness_mm = 1.0,
                    .max_edge_deviation_mm = 0.5};
  auto v = decide_verdict(in, s);
  // Spread 0.8 against 0.78 with U hypot(0.03, 0.04) = 0.05: undecided.
  EXPECT_EQ(v.bends[1].spread_decision, Conformity::kUndecided);
  EXPECT_TRUE(has_reason(v, "bend 1 angle spread along the bend 0.80 deg (U 0.050;"));
  EXPECT_EQ(v.bends[1].decision, Conformity::kConforming) << "its springback is its own";
  ASSERT_EQ(v.flanges.size(), 1u);
  EXPECT_EQ(v.flanges[0].shape_decision, Conformity::kUndecided);
  EXPECT_TRUE(has_reason(v, "flange 0 flatness 0.95 mm (U 0.100 mm) undecided"));
  EXPECT_TRUE(has_reason(v, "flange 0 curl radius -240.00 mm (U 30.000 mm) undecided"));
  EXPECT_TRUE(has_reason(v,
                         "flange 0 free edge off by 0.31 mm in-plane (U 0.050 mm), -0.52 mm "
                         "across (U 0.050 mm; undecided, within U of 0.50 mm)"));
  EXPECT_EQ(v.decision, PartDecision::kUndecided);
  // Tighter limits put each beyond its U: nonconforming.
  s.max_angle_spread_deg = 0.7;
  s.max_flatness_mm = 0.8;
  v = decide_verdict(in, s);
  EXPECT_EQ(v.bends[1].spread_decision, Conformity::kNonconforming);
  EXPECT_EQ(v.flanges[0].shape_decision, Conformity::kNonconforming);
  EXPECT_EQ(v.decision, PartDecision::kFail);
  // Looser ones put each inside by more than its U: conforming.
  s = {.max_angle_spread_deg = 0.9,
       .min_curl_radius_mm = 200.0,
       .max_flatness_mm = 1.1,
       .max_edge_deviation_mm = 0.6};
  v = decide_verdict(in, s);
  EXPECT_EQ(v.flanges[0].shape_decision, Conformity::kConforming);
  EXPECT_EQ(v.decision, PartDecision::kPass) << testing::PrintToString(v.reasons);
}

// A trim edge's limit reads its larger move; each move is placed against it with its own U (the
// result frame moves an edge in plane and across by different amounts).
TEST(Verdict, EachEdgeMoveMeetsTheLimitWithItsOwnU) {
  VerdictInput in = good_input();
  in.flanges = {{.flange_id = 0, .measured = true, .flatness_mm = 0.1}};
  const VerdictSettings s{.max_edge_deviation_mm = 0.5};
  // In plane 0.45 + 0.02 and across 0.10 + 0.30, both within 0.5: conforming. With the larger
  // U for both, 0.45 + 0.30 would straddle the limit.
  in.flanges[0].edges = {{"free", 0.45, 0.10, 0.30, 0.02, 0.30}};
  EXPECT_EQ(decide_verdict(in, s).flanges[0].shape_decision, Conformity::kConforming);
  in.flanges[0].edges = {{"free", 0.45, 0.10, 0.30, 0.30, 0.30}};
  EXPECT_EQ(decide_verdict(in, s).flanges[0].shape_decision, Conformity::kUndecided);
  // Across 0.62 beyond by more than its own U of 0.1: nonconforming whatever the in-plane U.
  in.flanges[0].edges = {{"free", 0.10, -0.62, 0.30, 0.30, 0.10}};
  const VerdictResult v = decide_verdict(in, s);
  EXPECT_EQ(v.flanges[0].shape_decision, Conformity::kNonconforming);
  EXPECT_TRUE(has_reason(v,
                         "flange 0 free edge off by 0.10 mm in-plane (U 0.300 mm), -0.62 mm "
                         "across (U 0.100 mm; limit 0.50 mm)"))
      << testing::PrintToString(v.reasons);
}

// Parts with one borderline bend (true springback within +-0.1 deg of its 1.0 deg tolerance)
// and one far inside, measured with errors within U, good and poor views: the part is never
// PASS when a true value is out of tolerance, never FAIL when all are within it.
TEST(Verdict, NeverAFalsePartDecisionOnBorderlineParts) {
  int pass = 0, fail = 0, undecided = 0;
  for (const double u : {0.01, 0.05, 0.15}) {
    for (int t = -10; t <= 10; ++t) {
      const double truth = 1.0 + 0.01 * t;
      for (int e = -2; e <= 2; ++e) {
        auto in = good_input();
        in.bends[0].springback_uncertainty_deg = 0.02;
        in.bends[1].springback_deg = truth + u * e / 2.0;
        in.bends[1].springback_uncertainty_deg = u;
        const auto v = decide_verdict(in);
        const bool good = truth <= 1.0;  // bend 0 (0.4 deg) is always within
        EXPECT_FALSE(v.decision == PartDecision::kPass && !good) << truth << " U " << u;
        EXPECT_FALSE(v.decision == PartDecision::kFail && good) << truth << " U " << u;
        pass += v.decision == PartDecision::kPass;
        fail += v.decision == PartDecision::kFail;
        undecided += v.decision == PartDecision::kUndecided;
      }
    }
  }
  EXPECT_GT(pass, 0);
  EXPECT_GT(fail, 0);
  EXPECT_GT(undecided, 0);
}

}  // namespace
}  // namespace springscan::analysis
