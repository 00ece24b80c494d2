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
  EXPECT_EQ(v.reasons.size(), 0u);
  ASSERT_EQ(v.bends.size(), 2u);
  EXPECT_TRUE(v.bends[0].pass && v.bends[1].pass);
  EXPECT_EQ(v.bends[1].bend_id, 1);
  EXPECT_EQ(v.bends[1].angle_tolerance_deg, 1.0);
}

TEST(Verdict, SurfaceDeviationByP95OrMax) {
  auto in = good_input();
  in.deviation.p95_mm = 0.84;
  auto v = decide_verdict(in);
  EXPECT_FALSE(v.pass);
  ASSERT_EQ(v.reasons.size(), 1u);
  EXPECT_EQ(v.reasons[0], "p95 |deviation| 0.84 mm > tolerance 0.50 mm");

  in = good_input();  // p95 fine, but one point is 0.61 mm off: only MAX sees it
  in.deviation.min_mm = -0.61;
  EXPECT_TRUE(decide_verdict(in).pass);
  v = decide_verdict(in, {.deviation_statistic = DeviationStatistic::kMax});
  EXPECT_FALSE(v.pass);
  EXPECT_TRUE(has_reason(v, "max |deviation| 0.61 mm > tolerance 0.50 mm"));
  EXPECT_TRUE(
      decide_verdict(in, {.tolerance_mm = 0.7, .deviation_statistic = DeviationStatistic::kMax})
          .pass);

  in = good_input();
  in.deviation.points = 0;
  EXPECT_TRUE(has_reason(decide_verdict(in), "no surface deviation"));
  in = good_input();
  in.deviation.p95_mm = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(decide_verdict(in).pass);
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
            "bend 1 springback -2.31 deg (nominal 90.00, measured 92.31) exceeds tolerance "
            "1.00 deg");
  EXPECT_TRUE(v.bends[0].pass);
  EXPECT_FALSE(v.bends[1].pass);
  EXPECT_TRUE(decide_verdict(in, {.angle_tolerance_deg = 2.5}).pass);
  // A per-bend tolerance wins.
  v = decide_verdict(in, {.angle_tolerance_deg_by_bend = {{1, 3.0}}});
  EXPECT_TRUE(v.pass);
  EXPECT_EQ(v.bends[1].angle_tolerance_deg, 3.0);
  EXPECT_EQ(v.bends[0].angle_tolerance_deg, 1.0);

  in = good_input();
  in.bends[0].measured = false;
  v = decide_verdict(in);
  EXPECT_TRUE(has_reason(v, "bend 0 not measured"));
  EXPECT_FALSE(v.bends[0].pass);  // an unmeasured bend never passes ...
  v = decide_verdict(in, {.fail_unmeasured_bends = false});
  EXPECT_TRUE(v.pass);  // ... but need not fail the part
  EXPECT_FALSE(v.bends[0].pass);
}

TEST(Verdict, AnalysisHealth) {
  auto in = good_input();
  in.field.coverage = 0.72;
  in.fit_rms_residual_mm = 1.32;
  const auto v = decide_verdict(in);
  EXPECT_FALSE(v.pass);
  ASSERT_EQ(v.reasons.size(), 2u);
  EXPECT_EQ(v.reasons[0], "deformation field coverage 0.72 < minimum 0.90 (min_cost_matching)");
  EXPECT_EQ(v.reasons[1],
            "global fit residual rms 1.32 mm > limit 1.00 mm: the analysis cannot be trusted");
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
  EXPECT_TRUE(has_reason(v, "bend 1 angle spread along the bend 0.80 deg (89.50 to 90.30)"));
  EXPECT_TRUE(has_reason(v, "flange 1 flatness 1.40 mm exceeds 1.00 mm"));
  EXPECT_TRUE(has_reason(v, "flange 1 curl radius -180.00 mm is tighter than 250.00 mm"));
  EXPECT_FALSE(has_reason(v, "flange 0"));
  EXPECT_FALSE(has_reason(v, "bend 0 angle spread"));
  EXPECT_TRUE(v.bends[1].pass) << "the bend's own pass is its springback";
  // The trim edges: off by default, then each edge's larger move against the limit.
  in.flanges[0].edges = {{"free", 0.31, -0.52}, {"side", -0.12, 0.2}};
  EXPECT_FALSE(has_reason(decide_verdict(in, s), "free edge"));
  VerdictSettings edge;
  edge.max_edge_deviation_mm = 0.5;
  EXPECT_TRUE(
      has_reason(decide_verdict(in, edge),
                 "flange 0 free edge off by 0.31 mm in-plane, -0.52 mm across (limit 0.50 mm)"));
  EXPECT_FALSE(has_reason(decide_verdict(in, edge), "side edge"));
  edge.max_edge_deviation_mm = 0.6;
  EXPECT_TRUE(decide_verdict(in, edge).pass);
  edge.max_edge_deviation_mm = 0.15;
  EXPECT_TRUE(
      has_reason(decide_verdict(in, edge),
                 "flange 0 side edge off by -0.12 mm in-plane, 0.20 mm across (limit 0.15 mm)"));
  // Within the limits: no reason.
  s.max_angle_spread_deg = 0.9;
  s.min_curl_radius_mm = 150.0;
  s.max_flatness_mm = 1.5;
  EXPECT_TRUE(decide_verdict(in, s).pass);
}

}  // namespace
}  // namespace springscan::analysis
