#include "report/msa_stats.hpp"

#include <algorithm>
#include <cmath>
#include <string>

namespace springscan::report {

namespace {

// The continued fraction of I_x(a, b) by the modified Lentz method (Press et al., Numerical
// Recipes, 3rd ed., section 6.4, eq. 6.4.5); converges fast for x < (a + 1) / (a + b + 2).
double beta_continued_fraction(double a, double b, double x) {
  constexpr double kTiny = 1e-300;
  constexpr double kEps = 1e-15;
  double c = 1.0;
  double d = 1.0 - (a + b) * x / (a + 1.0);
  d = 1.0 / (std::abs(d) < kTiny ? kTiny : d);
  double h = d;
  for (int m = 1; m <= 300; ++m) {
    const double dm = m;
    for (const bool odd : {false, true}) {
      // d_{2m} = m (b - m) x / ((a + 2m - 1)(a + 2m)); d_{2m+1} = -(a + m)(a + b + m) x / ...
      const double num = odd ? -(a + dm) * (a + b + dm) * x / ((a + 2 * dm) * (a + 2 * dm + 1))
                             : dm * (b - dm) * x / ((a + 2 * dm - 1) * (a + 2 * dm));
      d = 1.0 + num * d;
      d = 1.0 / (std::abs(d) < kTiny ? kTiny : d);
      c = 1.0 + num / c;
      if (std::abs(c) < kTiny) c = kTiny;
      const double step = c * d;
      h *= step;
      if (odd && std::abs(step - 1.0) < kEps) return h;
    }
  }
  return h;
}

double mean_of(const std::vector<double>& v) {
  double sum = 0.0;
  for (const double x : v) sum += x;
  return sum / static_cast<double>(v.size());
}

}  // namespace

double incomplete_beta(double a, double b, double x) {
  if (x <= 0.0) return 0.0;
  if (x >= 1.0) return 1.0;
  const double log_front =
      std::lgamma(a + b) - std::lgamma(a) - std::lgamma(b) + a * std::log(x) + b * std::log1p(-x);
  const double front = std::exp(log_front);
  // The symmetry I_x(a, b) = 1 - I_{1-x}(b, a) keeps the fraction on its fast side.
  if (x < (a + 1.0) / (a + b + 2.0)) return front * beta_continued_fraction(a, b, x) / a;
  return 1.0 - front * beta_continued_fraction(b, a, 1.0 - x) / b;
}

double student_t_two_sided_p(double t, double dof) {
  if (!std::isfinite(t)) return 0.0;
  // P(|T| >= |t|) = I_{dof / (dof + t^2)}(dof / 2, 1 / 2) (Abramowitz & Stegun 26.7.1, 26.5.27).
  return incomplete_beta(0.5 * dof, 0.5, dof / (dof + t * t));
}

analysis::Expected<Type1Figures> type1_figures(const std::vector<double>& values, double reference,
                                               double tolerance) {
  if (values.size() < 2)
    return analysis::fail("a type-1 study needs at least 2 values, got " +
                          std::to_string(values.size()));
  Type1Figures f;
  f.n = values.size();
  f.mean = mean_of(values);
  double ss = 0.0;
  for (const double x : values) ss += (x - f.mean) * (x - f.mean);
  f.stddev = std::sqrt(ss / static_cast<double>(f.n - 1));
  f.bias = f.mean - reference;
  if (f.stddev > 0.0) {
    f.bias_t = f.bias / (f.stddev / std::sqrt(static_cast<double>(f.n)));
    f.bias_p = student_t_two_sided_p(f.bias_t, static_cast<double>(f.n - 1));
    if (tolerance > 0.0) {
      // VDA 5 / Bosch booklet 10: 20 % of T against a 6 s spread, 10 % of T less the bias
      // against 3 s.
      f.cg = 0.2 * tolerance / (6.0 * f.stddev);
      f.cgk = (0.1 * tolerance - std::abs(f.bias)) / (3.0 * f.stddev);
    }
  } else {
    f.bias_p = f.bias == 0.0 ? 1.0 : 0.0;
  }
  return f;
}

bool type1_capable(const Type1Figures& f, const MsaLimits& limits) {
  return f.cg && f.cgk && *f.cg >= limits.min_cg && *f.cgk >= limits.min_cgk;
}

analysis::Expected<Type3Figures> type3_figures(const std::vector<std::vector<double>>& by_part,
                                               double tolerance) {
  if (by_part.size() < 2)
    return analysis::fail("a type-3 study needs at least 2 parts, got " +
                          std::to_string(by_part.size()));
  const std::size_t r = by_part.front().size();
  for (std::size_t i = 0; i < by_part.size(); ++i)
    if (by_part[i].size() != r)
      return analysis::fail("unbalanced study: part 1 has " + std::to_string(r) + " trials, part " +
                            std::to_string(i + 1) + " has " + std::to_string(by_part[i].size()));
  if (r < 2) return analysis::fail("a type-3 study needs at least 2 trials per part");
  Type3Figures f;
  f.parts = by_part.size();
  f.trials = r;
  std::vector<double> part_means;
  double grand = 0.0;
  for (const auto& trials : by_part) {
    part_means.push_back(mean_of(trials));
    grand += part_means.back();
  }
  grand /= static_cast<double>(f.parts);
  double ss_parts = 0.0, ss_within = 0.0;
  for (std::size_t i = 0; i < f.parts; ++i) {
    ss_parts += static_cast<double>(r) * (part_means[i] - grand) * (part_means[i] - grand);
    for (const double y : by_part[i]) ss_within += (y - part_means[i]) * (y - part_means[i]);
  }
  f.ms_parts = ss_parts / static_cast<double>(f.parts - 1);
  f.ms_within = ss_within / static_cast<double>(f.parts * (r - 1));
  f.ev = std::sqrt(f.ms_within);
  // The expected MS_parts is sigma_e^2 + r sigma_p^2, hence the part variance estimate; a
  // negative estimate means no part variation is visible and is taken as 0 (AIAG MSA).
  f.pv = std::sqrt(std::max(0.0, (f.ms_parts - f.ms_within) / static_cast<double>(r)));
  f.grr = f.ev;
  if (tolerance > 0.0) f.grr_pct_tolerance = 100.0 * 6.0 * f.grr / tolerance;
  const double tv = std::hypot(f.grr, f.pv);
  if (tv > 0.0) f.grr_pct_total = 100.0 * f.grr / tv;
  if (f.grr > 0.0) f.ndc = 1.41 * f.pv / f.grr;
  return f;
}

GrrVerdict grr_verdict(const Type3Figures& f, const MsaLimits& limits) {
  const std::optional<double> pct = f.grr_pct_tolerance ? f.grr_pct_tolerance : f.grr_pct_total;
  if (!pct) return GrrVerdict::kNotAcceptable;
  if (*pct <= limits.max_grr_pct) return GrrVerdict::kAcceptable;
  if (*pct <= limits.conditional_grr_pct) return GrrVerdict::kConditional;
  return GrrVerdict::kNotAcceptable;
}

const char* to_string(GrrVerdict verdict) {
  switch (verdict) {
    case GrrVerdict::kAcceptable:
      return "acceptable";
    case GrrVerdict::kConditional:
      return "conditionally acceptable";
    case GrrVerdict::kNotAcceptable:
      break;
  }
  return "not acceptable";
}

}  // namespace springscan::report
