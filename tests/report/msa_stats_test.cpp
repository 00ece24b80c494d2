// The gauge study statistics (report/msa_stats.hpp) against closed forms, values worked out by
// hand in the comments, Student-t table values, and data drawn from known distributions whose
// figures the test computes its own way.
#include "report/msa_stats.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace springscan::report {
namespace {

TEST(MsaStudentT, ClosedFormsAndTableValues) {
  EXPECT_DOUBLE_EQ(student_t_two_sided_p(0.0, 7.0), 1.0);
  // One degree of freedom is the Cauchy distribution: P(|T| >= 1) = 1/2.
  EXPECT_NEAR(student_t_two_sided_p(1.0, 1.0), 0.5, 1e-12);
  EXPECT_NEAR(student_t_two_sided_p(-1.0, 1.0), 0.5, 1e-12);
  // Two degrees of freedom: P(|T| >= t) = 1 - t / sqrt(2 + t^2).
  for (const double t : {0.3, 1.7, 4.0, 25.0})
    EXPECT_NEAR(student_t_two_sided_p(t, 2.0), 1.0 - t / std::sqrt(2.0 + t * t), 1e-12) << t;
  // Two-sided critical values t(1 - alpha/2, dof) from the usual tables (NIST/SEMATECH
  // e-Handbook 1.3.6.7.2): p = alpha there.
  EXPECT_NEAR(student_t_two_sided_p(2.063899, 24.0), 0.05, 1e-6);
  EXPECT_NEAR(student_t_two_sided_p(2.228139, 10.0), 0.05, 1e-6);
  EXPECT_NEAR(student_t_two_sided_p(2.009575, 49.0), 0.05, 1e-6);
  EXPECT_NEAR(student_t_two_sided_p(4.604095, 4.0), 0.01, 1e-6);
  EXPECT_NEAR(student_t_two_sided_p(1.710882, 24.0), 0.10, 1e-6);
  EXPECT_EQ(student_t_two_sided_p(INFINITY, 5.0), 0.0);
}

TEST(MsaIncompleteBeta, EndsAndSymmetry) {
  EXPECT_EQ(incomplete_beta(2.0, 3.0, 0.0), 0.0);
  EXPECT_EQ(incomplete_beta(2.0, 3.0, 1.0), 1.0);
  // I_x(1, 1) = x; I_x(a, 1) = x^a; I_x(a, b) = 1 - I_{1-x}(b, a).
  EXPECT_NEAR(incomplete_beta(1.0, 1.0, 0.37), 0.37, 1e-14);
  EXPECT_NEAR(incomplete_beta(3.5, 1.0, 0.6), std::pow(0.6, 3.5), 1e-13);
  EXPECT_NEAR(incomplete_beta(2.5, 7.0, 0.2) + incomplete_beta(7.0, 2.5, 0.8), 1.0, 1e-13);
}

TEST(MsaType1, ByHandAndRefusals) {
  // x = 1 2 3 4 5 against 2.5, T = 10: mean 3, s = sqrt(10/4), bias 0.5,
  // t = 0.5 / (s / sqrt 5) = 0.7071; Cg = 2 / (6 s); Cgk = (1 - 0.5) / (3 s).
  auto f = type1_figures({1, 2, 3, 4, 5}, 2.5, 10.0);
  ASSERT_TRUE(f.ok()) << f.message();
  const double s = std::sqrt(2.5);
  EXPECT_EQ(f->n, 5u);
  EXPECT_DOUBLE_EQ(f->mean, 3.0);
  EXPECT_NEAR(f->stddev, s, 1e-15);
  EXPECT_DOUBLE_EQ(f->bias, 0.5);
  EXPECT_NEAR(f->bias_t, 0.5 / (s / std::sqrt(5.0)), 1e-14);
  EXPECT_NEAR(*f->cg, 2.0 / (6.0 * s), 1e-14);
  EXPECT_NEAR(*f->cgk, 0.5 / (3.0 * s), 1e-14);
  EXPECT_FALSE(type1_capable(*f));
  // No tolerance: no Cg; no spread: no Cg either.
  EXPECT_FALSE(type1_figures({1, 2, 3}, 2.0, 0.0)->cg);
  EXPECT_FALSE(type1_figures({2, 2, 2}, 2.0, 1.0)->cg);
  EXPECT_FALSE(type1_figures({}, 0.0, 1.0).ok());
  EXPECT_FALSE(type1_figures({1.0}, 0.0, 1.0).ok());
}

// 2000 type-1 studies of 50 values drawn from N(reference + bias, sigma): each study's figures
// against the test's own one-pass sums, the mean of Cg against the true 0.2 T / (6 sigma), and
// the bias t-test's false alarms at 5 % without a bias (the p-value is right only if about 5 %).
TEST(MsaType1, DrawnFromAKnownDistribution) {
  std::mt19937 rng(42);
  const double sigma = 0.02, tolerance = 2.0, reference = 0.3;
  std::size_t false_alarms = 0, detected = 0;
  double cg_sum = 0.0;
  const int studies = 2000;
  for (int k = 0; k < studies; ++k) {
    const double bias = k % 2 == 0 ? 0.0 : 0.02;  // every other study: a bias of one sigma
    std::normal_distribution<double> draw(reference + bias, sigma);
    std::vector<double> x(50);
    long double sum = 0, sum2 = 0;
    for (double& v : x) {
      v = draw(rng);
      sum += v;
      sum2 += static_cast<long double>(v) * v;
    }
    const double n = 50.0;
    const double mean = static_cast<double>(sum / 50);
    const double s = static_cast<double>(std::sqrt((sum2 - sum * sum / 50) / 49));
    auto f = type1_figures(x, reference, tolerance);
    ASSERT_TRUE(f.ok());
    ASSERT_NEAR(f->mean, mean, 1e-12);
    ASSERT_NEAR(f->stddev, s, 1e-9);
    ASSERT_NEAR(*f->cg, 0.2 * tolerance / (6 * s), 1e-6);
    ASSERT_NEAR(*f->cgk, (0.1 * tolerance - std::abs(mean - reference)) / (3 * s), 1e-6);
    ASSERT_NEAR(f->bias_t, (mean - reference) / (s / std::sqrt(n)), 1e-6);
    const bool significant = f->bias_p < 0.05;
    if (bias == 0.0) {
      false_alarms += significant;
      cg_sum += *f->cg;
    } else {
      detected += significant;
    }
  }
  // Cg is 1/s times a constant, and for normal data with nu = n - 1 degrees of freedom
  // E[1/s] = sqrt(nu / 2) Gamma((nu - 1) / 2) / Gamma(nu / 2) / sigma (1.0156 / sigma at n = 50).
  const double nu = 49.0;
  const double inverse_s_bias =
      std::sqrt(nu / 2.0) * std::exp(std::lgamma((nu - 1.0) / 2.0) - std::lgamma(nu / 2.0));
  const double true_cg = 0.2 * tolerance / (6 * sigma);
  EXPECT_NEAR(cg_sum / (studies / 2) / true_cg, inverse_s_bias, 0.01);
  EXPECT_NEAR(static_cast<double>(false_alarms) / (studies / 2), 0.05, 0.015);
  // A one-sigma bias with n = 50 is found almost always (power > 0.99).
  EXPECT_GT(static_cast<double>(detected) / (studies / 2), 0.98);
}

TEST(MsaType3, ByHand) {
  // Parts {1, 3}, {2, 2}, {5, 7}: means 2, 2, 6, grand 10/3; SS_parts = 2 (2 (4/3)^2 + (8/3)^2)
  // = 64/3, MS_parts = 32/3; SS_within = 2 + 0 + 2, MS_within = 4 / (3 * 1) = 4/3.
  auto f = type3_figures({{1, 3}, {2, 2}, {5, 7}}, 6.0);
  ASSERT_TRUE(f.ok()) << f.message();
  EXPECT_NEAR(f->ms_parts, 32.0 / 3.0, 1e-13);
  EXPECT_NEAR(f->ms_within, 4.0 / 3.0, 1e-13);
  EXPECT_NEAR(f->ev, std::sqrt(4.0 / 3.0), 1e-13);
  EXPECT_NEAR(f->pv, std::sqrt((32.0 / 3.0 - 4.0 / 3.0) / 2.0), 1e-13);
  EXPECT_EQ(f->grr, f->ev);
  EXPECT_NEAR(*f->grr_pct_tolerance, 100.0 * 6.0 * std::sqrt(4.0 / 3.0) / 6.0, 1e-11);
  EXPECT_NEAR(*f->grr_pct_total, 100.0 * std::sqrt((4.0 / 3.0) / (4.0 / 3.0 + 14.0 / 3.0)), 1e-11);
  EXPECT_NEAR(*f->ndc, 1.41 * std::sqrt(14.0 / 3.0) / std::sqrt(4.0 / 3.0), 1e-12);
  EXPECT_EQ(grr_verdict(*f), GrrVerdict::kNotAcceptable);
  // Parts that differ less than the repeats: PV is 0, not imaginary.
  auto flat = type3_figures({{0, 2}, {2, 0}, {1, 1}}, 0.0);
  ASSERT_TRUE(flat.ok());
  EXPECT_EQ(flat->pv, 0.0);
  EXPECT_NEAR(*flat->grr_pct_total, 100.0, 1e-12);
  EXPECT_FALSE(flat->grr_pct_tolerance);
}

TEST(MsaType3, Refusals) {
  EXPECT_FALSE(type3_figures({}, 1.0).ok());
  EXPECT_FALSE(type3_figures({{1, 2}}, 1.0).ok());
  EXPECT_FALSE(type3_figures({{1}, {2}}, 1.0).ok());
  auto unbalanced = type3_figures({{1, 2}, {1, 2, 3}}, 1.0);
  ASSERT_FALSE(unbalanced.ok());
  EXPECT_TRUE(unbalanced.error().is_invalid_input());
}

// 200 parts from N(0, sigma_p), 3 trials each with N(0, sigma_e) repeat error: the figures
// against the test's own sums (total minus between), and EV, PV against the true sigmas.
TEST(MsaType3, DrawnFromAKnownDistribution) {
  std::mt19937 rng(7);
  const double sigma_p = 0.05, sigma_e = 0.01;
  std::normal_distribution<double> part(0.0, sigma_p), repeat(0.0, sigma_e);
  const std::size_t p = 200, r = 3;
  std::vector<std::vector<double>> y(p);
  long double total = 0, total2 = 0, between2 = 0;
  for (auto& trials : y) {
    const double truth = 1.0 + part(rng);
    long double part_sum = 0;
    for (std::size_t j = 0; j < r; ++j) {
      trials.push_back(truth + repeat(rng));
      part_sum += trials.back();
      total += trials.back();
      total2 += static_cast<long double>(trials.back()) * trials.back();
    }
    between2 += part_sum * part_sum / r;
  }
  const long double n = p * r;
  const long double ss_total = total2 - total * total / n;
  const long double ss_parts = between2 - total * total / n;
  const double ms_within = static_cast<double>((ss_total - ss_parts) / (p * (r - 1)));
  const double ms_parts = static_cast<double>(ss_parts / (p - 1));
  auto f = type3_figures(y, 0.6);
  ASSERT_TRUE(f.ok());
  EXPECT_NEAR(f->ms_within / ms_within, 1.0, 1e-6);
  EXPECT_NEAR(f->ms_parts / ms_parts, 1.0, 1e-6);
  EXPECT_NEAR(f->ev / sigma_e, 1.0, 0.08);  // 400 degrees of freedom: sd of EV/sigma ~ 3.5 %
  EXPECT_NEAR(f->pv / sigma_p, 1.0, 0.15);  // 199 degrees of freedom: ~ 5 %
  EXPECT_NEAR(*f->grr_pct_tolerance, 100.0 * 6.0 * f->ev / 0.6, 1e-9);
  EXPECT_NEAR(*f->ndc, 1.41 * f->pv / f->ev, 1e-12);
  // True %GRR of T = 10 % at this sigma_e; the verdict is near its limit, so only check it
  // exists with the right limits around it.
  EXPECT_NEAR(*f->grr_pct_tolerance, 10.0, 1.0);
}

}  // namespace
}  // namespace springscan::report
