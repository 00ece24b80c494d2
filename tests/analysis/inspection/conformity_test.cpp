// The decision rule against constructed truth: under the guard band a decision is never false
// when the true value lies within U of the measured one, and UNDECIDED is said only where the
// interval [v - U, v + U] really straddles the limit. SIMPLE shows what the guard band prevents.
#include "analysis/inspection/conformity.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <ostream>

namespace springscan::analysis {
namespace {}  // namespace

// Readable failures: the outcome's name, not its bytes.
void PrintTo(Conformity c, std::ostream* os) { *os << to_string(c); }

namespace {

constexpr auto kGuard = DecisionRule::kGuardBand;
constexpr auto kSimple = DecisionRule::kSimple;
constexpr auto kC = Conformity::kConforming;
constexpr auto kN = Conformity::kNonconforming;
constexpr auto kU = Conformity::kUndecided;

TEST(Conformity, UpperLimitTable) {
  struct Row {
    double value, u;
    Conformity guard, simple;
  };
  // Limit 1.0 deg, U 0.1: conforming up to 0.9, nonconforming beyond 1.1 (ISO 14253-1).
  const Row rows[] = {
      {0.0, 0.1, kC, kC},   {0.85, 0.1, kC, kC}, {0.9, 0.1, kC, kC},  {0.901, 0.1, kU, kC},
      {0.99, 0.1, kU, kC},  {1.0, 0.1, kU, kC},  {1.01, 0.1, kU, kN}, {1.1, 0.1, kU, kN},
      {1.101, 0.1, kN, kN}, {2.0, 0.1, kN, kN},  {0.99, 0.0, kC, kC}, {1.01, 0.0, kN, kN},
      {0.99, 0.5, kU, kC},  {0.6, 0.5, kU, kC},  {0.4, 0.5, kC, kC},  {1.6, 0.5, kN, kN},
      {1.0, 0.0, kC, kC},
  };
  for (const Row& r : rows) {
    EXPECT_EQ(judge_at_most(r.value, r.u, 1.0, kGuard), r.guard) << r.value << " U " << r.u;
    EXPECT_EQ(judge_at_most(r.value, r.u, 1.0, kSimple), r.simple) << r.value << " U " << r.u;
  }
}

TEST(Conformity, LowerLimitTable) {
  // A least curl radius of 250 mm, U 20 mm.
  EXPECT_EQ(judge_at_least(400.0, 20.0, 250.0, kGuard), kC);
  EXPECT_EQ(judge_at_least(270.0, 20.0, 250.0, kGuard), kC);
  EXPECT_EQ(judge_at_least(260.0, 20.0, 250.0, kGuard), kU);
  EXPECT_EQ(judge_at_least(240.0, 20.0, 250.0, kGuard), kU);
  EXPECT_EQ(judge_at_least(230.0, 20.0, 250.0, kGuard), kU);
  EXPECT_EQ(judge_at_least(229.0, 20.0, 250.0, kGuard), kN);
  EXPECT_EQ(judge_at_least(240.0, 20.0, 250.0, kSimple), kN);
  EXPECT_EQ(judge_at_least(260.0, 20.0, 250.0, kSimple), kC);
}

// A value or U that cannot be placed is never decided by the guard band; SIMPLE fails the value
// as the verdict did before U existed, and ignores U.
TEST(Conformity, NotANumberOrANegativeUncertaintyDecidesNothing) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  EXPECT_EQ(judge_at_most(nan, 0.1, 1.0, kGuard), kU);
  EXPECT_EQ(judge_at_most(0.1, nan, 1.0, kGuard), kU);
  EXPECT_EQ(judge_at_most(5.0, nan, 1.0, kGuard), kU);
  EXPECT_EQ(judge_at_most(0.1, -0.2, 1.0, kGuard), kU);
  EXPECT_EQ(judge_at_most(0.1, inf, 1.0, kGuard), kU);
  EXPECT_EQ(judge_at_least(nan, 1.0, 250.0, kGuard), kU);
  EXPECT_EQ(judge_at_least(400.0, nan, 250.0, kGuard), kU);
  EXPECT_EQ(judge_at_most(nan, 0.1, 1.0, kSimple), kN);
  EXPECT_EQ(judge_at_most(0.1, nan, 1.0, kSimple), kC);
  EXPECT_EQ(judge_at_least(nan, 1.0, 250.0, kSimple), kN);
}

TEST(Conformity, WorstOrdersTheOutcomes) {
  EXPECT_EQ(worst(Conformity::kNotJudged, kC), kC);
  EXPECT_EQ(worst(kC, kU), kU);
  EXPECT_EQ(worst(kN, kU), kN);
  EXPECT_EQ(worst(kU, kN), kN);
  EXPECT_EQ(worst(Conformity::kNotJudged, Conformity::kNotJudged), Conformity::kNotJudged);
  EXPECT_STREQ(to_string(kU), "UNDECIDED");
  EXPECT_STREQ(to_string(PartDecision::kPass), "PASS");
  EXPECT_STREQ(to_string(kGuard), "GUARD_BAND");
}

// Borderline cases: true springback within +-0.1 deg of a 1.0 deg tolerance, measured with an
// error anywhere in [-U, U] (an honest U), for a tight and a poor view. The guard band never
// calls a part in tolerance NONCONFORMING nor one out of tolerance CONFORMING, and says
// UNDECIDED only where [v - U, v + U] holds the limit. SIMPLE, on the same table, does decide
// falsely (the test can fail).
TEST(Conformity, NeverAFalseDecisionOnBorderlineCases) {
  const double limit = 1.0;
  int guard_false = 0, simple_false = 0, undecided = 0, decided = 0;
  for (const double u : {0.005, 0.02, 0.05, 0.1, 0.3}) {
    for (int t = -100; t <= 100; ++t) {
      const double truth = limit + 0.001 * t;
      for (const double sign : {1.0, -1.0}) {  // springback either way
        for (int e = -4; e <= 4; ++e) {
          const double error = u * e / 4.0;
          const double measured = sign * truth + error;
          const bool in_tolerance = std::abs(truth) <= limit;
          const Conformity g = judge_at_most(std::abs(measured), u, limit, kGuard);
          const Conformity s = judge_at_most(std::abs(measured), u, limit, kSimple);
          guard_false += (g == kC && !in_tolerance) || (g == kN && in_tolerance);
          simple_false += (s == kC && !in_tolerance) || (s == kN && in_tolerance);
          if (g == kU) {
            ++undecided;
            EXPECT_TRUE(std::abs(measured) - u <= limit && limit <= std::abs(measured) + u)
                << "undecided, but the interval does not straddle: " << measured << " U " << u;
          } else {
            ++decided;
          }
        }
      }
    }
  }
  EXPECT_EQ(guard_false, 0);
  EXPECT_GT(simple_false, 0) << "the table must hold cases the value alone gets wrong";
  EXPECT_GT(decided, 0);
  EXPECT_GT(undecided, 0);
}

}  // namespace
}  // namespace springscan::analysis
