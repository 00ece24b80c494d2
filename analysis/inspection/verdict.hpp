#pragma once
// The verdict (DESIGN.md stage 9, issue 6): pass/fail of one inspection from the filled report,
// with every failing rule in verdict.reasons and its numbers, so the operator and the PLC log
// see why ("p95 |deviation| 0.84 mm > tolerance 0.50 mm").
//
// Rules (each one that fails adds a reason; the part passes when there is none):
//   surface   the p95 or the maximum of |signed deviation| (selectable) <= tolerance_mm;
//             no deviation computed at all fails;
//   bends     |springback_deg| <= the bend's angle_tolerance_deg when set (> 0), else the
//             setting; a bend that could not be measured fails when fail_unmeasured_bends;
//   health    the deformation field covers >= min_coverage of the reduced model (when a field
//             was computed), and the global fit's residual rms to the surface (rms_residual:
//             the trimmed deviation rms; not rms_final, which grows with the sample spacing) <=
//             max_fit_rms_mm, and the orientation is not ambiguous (global_fit.ambiguous):
//             otherwise the numbers above cannot be trusted.
//
// Thread safety: pure function.

#include "proto/springscan.pb.h"

namespace springscan::analysis {

enum class DeviationStatistic {
  kP95,  ///< 95th percentile of |signed distance| (robust to single outliers)
  kMax,  ///< maximum |signed distance| (strict)
};

struct VerdictSettings {
  double tolerance_mm = 0.5;                                          ///< surface deviation limit
  double angle_tolerance_deg = 1.0;                                   ///< springback limit per bend
  DeviationStatistic deviation_statistic = DeviationStatistic::kP95;  ///< what is compared
  double min_coverage = 0.9;          ///< least share of the reduced model with a field vector
  double max_fit_rms_mm = 1.0;        ///< largest global fit residual rms (scan to surface)
                                      ///< that still counts as a good fit
  bool fail_unmeasured_bends = true;  ///< a bend without a measurement fails the part
};

/// Decides pass/fail from `report` (deviation, bends, deformation_field, global_fit filled).
v1::Verdict decide_verdict(const v1::InspectionReport& report,
                           const VerdictSettings& settings = {});

}  // namespace springscan::analysis
