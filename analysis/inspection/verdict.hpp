#pragma once
// The verdict (DESIGN.md stage 9): the decision on one inspection from the stage results, with
// every characteristic that does not conform in the reasons, its value, its expanded
// uncertainty U and its limit, so the operator and the PLC log see why
// ("p95 |deviation| 0.84 mm (U 0.020 mm) > tolerance 0.50 mm"). VerdictSettings is the one
// owner of the tolerances and of the decision rule: the deviation and springback stages measure
// (and give U), only the verdict judges, and the report copies its decisions
// (verdict_proto.hpp), per bend and per flange too.
//
// Each characteristic is judged by the decision rule (conformity.hpp): under GUARD_BAND (the
// default, ISO 14253-1) CONFORMING when |v| <= T - U, NONCONFORMING when |v| > T + U, else
// UNDECIDED; under SIMPLE the value alone. Characteristics (each one not conforming adds a
// reason):
//   surface   the p95 or the maximum of |signed deviation| (selectable) <= tolerance, with the U
//             of that statistic; no deviation computed at all fails the part;
//   bends     |springback_deg| <= the bend's limit (angle_tolerance_deg_by_bend, else
//             angle_tolerance_deg), U springback_uncertainty_deg; a measurable bend that could
//             not be measured is UNDECIDED (never a silent pass), and fails the part only when
//             fail_unmeasured_bends; a closed hem (not measurable) is not judged;
//   shape     (each off at 0) per bend the spread of its angle along the bend <=
//             max_angle_spread_deg (U: the root sum of squares of the U of the two stations
//             that span it); per flange its flatness <= max_flatness_mm and, when it is
//             curled, |curl radius| >= min_curl_radius_mm; each measured trim edge (an end
//             flange's free edge, a side edge) within max_edge_deviation_mm of the CAD edge,
//             in-plane and across;
//   health    the deformation field covers >= min_coverage of the reduced model (when a field
//             was computed), and the global fit's residual rms to the surface (the trimmed
//             deviation rms; not rms_final, which grows with the sample spacing) <=
//             max_fit_rms_mm, and the orientation is not ambiguous (global_fit.ambiguous):
//             otherwise the numbers above cannot be trusted, and the part fails. These are not
//             measurements against a tolerance; the decision rule does not apply to them.
// The part: FAIL when any characteristic is NONCONFORMING or a rule fails the part outright
// (health, no deviation, fail_unmeasured_bends), else UNDECIDED when any is UNDECIDED, else
// PASS. `pass` is true only for PASS.
//
// Thread safety: pure function.

#include <cstddef>
#include <map>
#include <span>
#include <string>
#include <vector>

#include "analysis/deviation/deviation.hpp"
#include "analysis/inspection/conformity.hpp"
#include "analysis/springback/springback.hpp"

namespace springscan::analysis {

enum class DeviationStatistic {
  kP95,  ///< 95th percentile of |signed distance| (robust to single outliers)
  kMax,  ///< maximum |signed distance| (strict)
};

struct VerdictSettings {
  double tolerance_mm = 0.5;                                          ///< surface deviation limit
  double angle_tolerance_deg = 1.0;                                   ///< springback limit per bend
  std::map<int, double> angle_tolerance_deg_by_bend{};                ///< bend id -> its own limit
  DeviationStatistic deviation_statistic = DeviationStatistic::kP95;  ///< what is compared
  double min_coverage = 0.9;    ///< least share of the reduced model with a field vector
  double max_fit_rms_mm = 1.0;  ///< largest global fit residual rms (scan to surface)
                                ///< that still counts as a good fit
  /// A measurable bend without a measurement is UNDECIDED either way; true also fails the
  /// part (a line that scraps rather than re-measures), false leaves the part UNDECIDED.
  bool fail_unmeasured_bends = false;
  double max_angle_spread_deg = 0.0;   ///< bend angle max - min along a bend; 0: not checked
  double min_curl_radius_mm = 0.0;     ///< least |curl radius| of a curled flange; 0: not checked
  double max_flatness_mm = 0.0;        ///< largest flange flatness (max distance); 0: not checked
  double max_edge_deviation_mm = 0.0;  ///< largest |move| of a trim edge; 0: not checked
  DecisionRule decision_rule = DecisionRule::kGuardBand;  ///< how a value meets its limit
};

/// One measured trim edge of a flange (springback stage, FlangeFit::trim_edges).
struct EdgeSummary {
  std::string kind;             ///< "free" or "side" (edge_kind_name), for the reason
  double in_plane_mm = 0.0;     ///< its in-plane move of largest magnitude (signed)
  double across_mm = 0.0;       ///< its move across of largest magnitude (signed)
  double uncertainty_mm = 0.0;  ///< expanded U (k = 2) of the larger of the two
  /// Each move's own U (k = 2); 0: uncertainty_mm stands for both.
  double in_plane_uncertainty_mm = 0.0, across_uncertainty_mm = 0.0;
};

/// What the shape rules need of one flange (springback stage, FlangeFit::shape).
struct FlangeShapeSummary {
  int flange_id = -1;
  bool measured = false;
  double flatness_mm = 0.0;  ///< max distance from its plane
  bool curled = false;
  double curl_radius_mm = 0.0;              ///< signed; meaningful when curled
  double flatness_uncertainty_mm = 0.0;     ///< expanded U (k = 2) of flatness_mm
  double curl_radius_uncertainty_mm = 0.0;  ///< expanded U (k = 2) of curl_radius_mm
  std::vector<EdgeSummary> edges{};         ///< its measured trim edges
};

/// How much of the reduced model the deformation field covers (matching stage).
struct FieldCoverage {
  double coverage = 0.0;         ///< share of the reduced model points with a vector
  std::size_t model_points = 0;  ///< reduced model points; 0: no field computed (not judged)
  std::string method{};          ///< to_string(CorrespondenceMethod), for the reason
};

/// The stage results the verdict is computed from. Borrows `signed_distance_mm` (it must
/// outlive the call); the rest are copies of small structs.
struct VerdictInput {
  DeviationStatistics deviation{};               ///< deviation stage; points 0: none computed
  std::span<const double> signed_distance_mm{};  ///< deviation stage, for the share out of
                                                 ///< tolerance; may be empty
  std::vector<BendMeasurement> bends{};          ///< springback stage, in report order
  std::vector<FlangeShapeSummary> flanges{};     ///< springback stage, for the shape rules
  FieldCoverage field{};                         ///< deformation field stage
  double fit_rms_residual_mm = 0.0;              ///< global fit: trimmed deviation rms, mm
  bool orientation_ambiguous = false;            ///< global fit: two orientations fit alike
  double orientation_ambiguity = 0.0;            ///< global fit: their error ratio, for the reason
};

/// The decision on one bend.
struct BendVerdict {
  int bend_id = -1;
  double angle_tolerance_deg = 0.0;  ///< the limit applied
  /// decision CONFORMING, or a closed hem (not judged): the report's and the PLC's bend pass.
  bool pass = false;
  Conformity decision = Conformity::kNotJudged;         ///< |springback| against its limit
  Conformity spread_decision = Conformity::kNotJudged;  ///< angle spread (max_angle_spread_deg)
};

/// The shape decision on one flange: the worst of its flatness, curl and trim edges.
struct FlangeVerdict {
  int flange_id = -1;
  Conformity shape_decision = Conformity::kNotJudged;  ///< not judged: no shape limit applies
};

struct VerdictResult {
  PartDecision decision = PartDecision::kFail;            ///< see the header comment
  bool pass = false;                                      ///< decision == kPass
  DecisionRule decision_rule = DecisionRule::kGuardBand;  ///< the rule that decided
  std::vector<std::string> reasons{};  ///< one per characteristic not conforming, per failed rule
  double tolerance_mm = 0.0;           ///< the surface limit applied
  double fraction_out_of_tolerance = 0.0;  ///< share of signed_distance_mm with |d| > limit
  Conformity surface_decision = Conformity::kNotJudged;  ///< not judged: no deviation computed
  double surface_uncertainty_mm = 0.0;   ///< U of the statistic the surface criterion uses
  std::vector<BendVerdict> bends{};      ///< one per input bend, in the same order
  std::vector<FlangeVerdict> flanges{};  ///< one per input flange, in the same order
};

/// The shape summaries of the springback stage's flanges.
std::vector<FlangeShapeSummary> flange_shapes(const std::vector<FlangeFit>& flanges);

/// Decides PASS, FAIL or UNDECIDED from the stage results.
VerdictResult decide_verdict(const VerdictInput& input, const VerdictSettings& settings = {});

}  // namespace springscan::analysis
