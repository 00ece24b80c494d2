#pragma once
// The statistics of the gauge capability studies (`springscan msa`, report/msa.hpp): pure
// functions over numbers, no reports. Formulas as issue 42 and docs/calibration.md give them:
//
// Type 1 (VDA 5 section 5.2; AIAG MSA 4th ed., "Bias" and "Cg/Cgk" of a reference part):
//   s with n - 1; bias = mean - reference; t = bias / (s / sqrt(n)), two-sided p with n - 1
//   degrees of freedom; Cg = 0.2 T / (6 s), Cgk = (0.1 T - |bias|) / (3 s).
// Type 3 (AIAG MSA 4th ed., ANOVA method, with the operator term left out: an automated gauge):
//   a one-way ANOVA of p parts with r trials each,
//   MS_parts = r sum_i (mean_i - mean)^2 / (p - 1), MS_within = sum_ij (y_ij - mean_i)^2 / (p (r -
//   1)), EV = sqrt(MS_within), PV = sqrt(max(0, (MS_parts - MS_within) / r)), GRR = EV, %GRR(T) =
//   100 * 6 GRR / T, %GRR(TV) = 100 GRR / sqrt(GRR^2 + PV^2), ndc = 1.41 PV / GRR.
//
// Thread safety: every function is pure.

#include <optional>
#include <vector>

#include "analysis/core/expected.hpp"

namespace springscan::report {

/// The usual acceptance limits (VDA 5, AIAG MSA). Defaults are the limits the issue names.
struct MsaLimits {
  double min_cg = 1.33;               ///< type 1: Cg at least this
  double min_cgk = 1.33;              ///< type 1: Cgk at least this
  double bias_alpha = 0.05;           ///< type 1: bias significant when p < this
  double max_grr_pct = 10.0;          ///< type 3: %GRR of the tolerance up to this: acceptable
  double conditional_grr_pct = 30.0;  ///< ... up to this: conditionally acceptable
  double min_ndc = 5.0;               ///< type 3: number of distinct categories at least this
};

struct Type1Figures {
  std::size_t n = 0;
  double mean = 0.0;
  double stddev = 0.0;        ///< s, n - 1 in the denominator
  double bias = 0.0;          ///< mean - reference
  double bias_t = 0.0;        ///< 0 when s = 0
  double bias_p = 1.0;        ///< two-sided p of the bias t-test
  std::optional<double> cg;   ///< needs T > 0 and s > 0
  std::optional<double> cgk;  ///< needs T > 0 and s > 0
};

/// Type 1 figures of `values` (one reference part measured repeatedly) against `reference`
/// with tolerance width `tolerance` (T; 0: none). Needs at least 2 values.
analysis::Expected<Type1Figures> type1_figures(const std::vector<double>& values, double reference,
                                               double tolerance);

/// Cg and Cgk both at least the limits.
bool type1_capable(const Type1Figures& f, const MsaLimits& limits = {});

struct Type3Figures {
  std::size_t parts = 0;
  std::size_t trials = 0;
  double ms_parts = 0.0;
  double ms_within = 0.0;
  double ev = 0.0;
  double pv = 0.0;
  double grr = 0.0;
  std::optional<double> grr_pct_tolerance;  ///< needs T > 0
  std::optional<double> grr_pct_total;      ///< needs GRR^2 + PV^2 > 0
  std::optional<double> ndc;                ///< needs GRR > 0
};

/// Type 3 figures of `by_part[i][j]`, part i, trial j: at least 2 parts and 2 trials, every
/// part with the same number of trials (a balanced study), else an error saying which.
analysis::Expected<Type3Figures> type3_figures(const std::vector<std::vector<double>>& by_part,
                                               double tolerance);

enum class GrrVerdict { kAcceptable, kConditional, kNotAcceptable };

/// By %GRR of the tolerance (or, without a tolerance, of the total variation).
GrrVerdict grr_verdict(const Type3Figures& f, const MsaLimits& limits = {});
const char* to_string(GrrVerdict verdict);

/// Two-sided p-value of Student's t with `dof` degrees of freedom: P(|T| >= |t|).
double student_t_two_sided_p(double t, double dof);

/// The regularized incomplete beta function I_x(a, b), a, b > 0, 0 <= x <= 1.
double incomplete_beta(double a, double b, double x);

}  // namespace springscan::report
