// The inspection verdict (verdict.hpp): each characteristic judged by the decision rule, one
// reason per characteristic that does not conform (value, U, limit) and per failed health rule.
#include "analysis/inspection/verdict.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

namespace springscan::analysis {
namespace {

std::string fixed(double x, int decimals) {
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, "%.*f", decimals, x);
  return buffer;
}

std::string fixed2(double x) { return fixed(x, 2); }

// U to a thousandth: a bend's U is a few hundredths of a degree.
std::string with_u(double u) { return "U " + fixed(u, 3); }

// The relation the reason states: the limit broken, or the value within U of it.
std::string relation(Conformity c, const std::string& broken) {
  return c == Conformity::kUndecided ? "undecided, within U of" : broken;
}

bool decided_against(Conformity c) {
  return c == Conformity::kNonconforming || c == Conformity::kUndecided;
}

// Share of |d| beyond the limit; a fixed serial order, so the figure is reproducible.
double fraction_beyond(std::span<const double> d, double limit) {
  if (d.empty()) return 0.0;
  const auto out =
      std::count_if(d.begin(), d.end(), [limit](double v) { return std::abs(v) > limit; });
  return static_cast<double>(out) / static_cast<double>(d.size());
}

// The judgement of the part so far: a characteristic that does not conform, or a rule that
// fails the part outright.
struct Tally {
  bool failed = false;
  bool undecided = false;
  void add(Conformity c) {
    failed = failed || c == Conformity::kNonconforming;
    undecided = undecided || c == Conformity::kUndecided;
  }
};

void check_surface(const VerdictInput& in, const VerdictSettings& s, VerdictResult& out,
                   Tally& tally) {
  out.tolerance_mm = s.tolerance_mm;
  out.fraction_out_of_tolerance = fraction_beyond(in.signed_distance_mm, s.tolerance_mm);
  const DeviationStatistics& d = in.deviation;
  if (d.points == 0) {
    out.reasons.push_back("no surface deviation was computed (0 scan points compared)");
    tally.failed = true;
    return;
  }
  const bool p95 = s.deviation_statistic == DeviationStatistic::kP95;
  const double value = p95 ? d.p95_mm : std::max(std::abs(d.min_mm), std::abs(d.max_mm));
  const double u = p95 ? d.p95_uncertainty_mm : d.max_uncertainty_mm;
  out.surface_uncertainty_mm = u;
  out.surface_decision = judge_at_most(value, u, s.tolerance_mm, s.decision_rule);
  tally.add(out.surface_decision);
  if (decided_against(out.surface_decision)) {
    out.reasons.push_back(std::string(p95 ? "p95" : "max") + " |deviation| " + fixed2(value) +
                          " mm (" + with_u(u) + " mm) " + relation(out.surface_decision, ">") +
                          " tolerance " + fixed2(s.tolerance_mm) + " mm");
  }
}

// The spread of the angle along a bend and its U: the stations at its two ends each carry
// their own U; the spread is their difference (root sum of squares: the stations' fits are
// independent, and a common term that cancels in the difference only makes this larger).
double spread_uncertainty(const BendMeasurement& bend) {
  const auto by_angle = [](const BendStation& a, const BendStation& b) {
    return a.angle_deg < b.angle_deg;
  };
  const auto [low, high] =
      std::minmax_element(bend.stations.begin(), bend.stations.end(), by_angle);
  return std::hypot(low->angle_uncertainty_deg, high->angle_uncertainty_deg);
}

BendVerdict judge_bend(const BendMeasurement& bend, const VerdictSettings& s,
                       std::vector<std::string>& reasons, Tally& tally) {
  const auto own = s.angle_tolerance_deg_by_bend.find(bend.bend_id);
  const double tolerance =
      own != s.angle_tolerance_deg_by_bend.end() ? own->second : s.angle_tolerance_deg;
  BendVerdict v{bend.bend_id, tolerance, false};
  const std::string name = "bend " + std::to_string(bend.bend_id);
  if (!bend.measurable) {
    v.pass = true;  // a closed hem: listed, not judged, never failing the part by itself
    return v;
  }
  if (!bend.measured) {
    // The station cannot tell: never a silent pass.
    v.decision = Conformity::kUndecided;
    tally.add(v.decision);
    const std::string what = bend.status.empty() ? name + " not measured" : bend.status;
    if (s.fail_unmeasured_bends) tally.failed = true;
    reasons.push_back(what + (s.fail_unmeasured_bends ? " (fails the part: fail_unmeasured_bends)"
                                                      : " (undecided)"));
    return v;
  }
  const double u = bend.springback_uncertainty_deg;
  v.decision = judge_at_most(std::abs(bend.springback_deg), u, tolerance, s.decision_rule);
  v.pass = v.decision == Conformity::kConforming;
  tally.add(v.decision);
  if (decided_against(v.decision)) {
    reasons.push_back(name + " springback " + fixed2(bend.springback_deg) + " deg (" + with_u(u) +
                      "; nominal " + fixed2(bend.nominal_angle_deg) + ", measured " +
                      fixed2(bend.measured_angle_deg) + ") " + relation(v.decision, "exceeds") +
                      " tolerance " + fixed2(tolerance) + " deg");
  }
  if (s.max_angle_spread_deg > 0.0 && !bend.stations.empty()) {
    const double su = spread_uncertainty(bend);
    v.spread_decision =
        judge_at_most(bend.angle_spread_deg, su, s.max_angle_spread_deg, s.decision_rule);
    tally.add(v.spread_decision);
    if (decided_against(v.spread_decision)) {
      reasons.push_back(name + " angle spread along the bend " + fixed2(bend.angle_spread_deg) +
                        " deg (" + with_u(su) + "; " + fixed2(bend.angle_min_deg) + " to " +
                        fixed2(bend.angle_max_deg) + ") " + relation(v.spread_decision, "exceeds") +
                        " " + fixed2(s.max_angle_spread_deg) + " deg");
    }
  }
  return v;
}

FlangeVerdict judge_flange(const FlangeShapeSummary& f, const VerdictSettings& s,
                           std::vector<std::string>& reasons, Tally& tally) {
  FlangeVerdict v{f.flange_id};
  if (!f.measured) return v;
  const std::string name = "flange " + std::to_string(f.flange_id);
  const DecisionRule rule = s.decision_rule;
  const auto note = [&](Conformity c, const std::string& reason) {
    v.shape_decision = worst(v.shape_decision, c);
    tally.add(c);
    if (decided_against(c)) reasons.push_back(reason);
  };
  if (s.max_edge_deviation_mm > 0.0) {
    for (const EdgeSummary& e : f.edges) {
      // The limit reads the larger move: each move against it with its own U (both within by
      // more than their U conforms; either beyond by more than its U does not).
      const double u_in =
          e.in_plane_uncertainty_mm > 0.0 ? e.in_plane_uncertainty_mm : e.uncertainty_mm;
      const double u_across =
          e.across_uncertainty_mm > 0.0 ? e.across_uncertainty_mm : e.uncertainty_mm;
      const double limit = s.max_edge_deviation_mm;
      const Conformity c = worst(judge_at_most(std::abs(e.in_plane_mm), u_in, limit, rule),
                                 judge_at_most(std::abs(e.across_mm), u_across, limit, rule));
      note(c, name + " " + e.kind + " edge off by " + fixed2(e.in_plane_mm) + " mm in-plane (" +
                  with_u(u_in) + " mm), " + fixed2(e.across_mm) + " mm across (" +
                  with_u(u_across) + " mm; " + relation(c, "limit") + " " + fixed2(limit) + " mm)");
    }
  }
  if (s.max_flatness_mm > 0.0) {
    const double u = f.flatness_uncertainty_mm;
    const Conformity c = judge_at_most(f.flatness_mm, u, s.max_flatness_mm, rule);
    note(c, name + " flatness " + fixed2(f.flatness_mm) + " mm (" + with_u(u) + " mm) " +
                relation(c, "exceeds") + " " + fixed2(s.max_flatness_mm) + " mm");
  }
  if (s.min_curl_radius_mm > 0.0) {
    // A flange flat within noise has no curl radius to judge: it conforms.
    const double u = f.curl_radius_uncertainty_mm;
    const Conformity c =
        f.curled ? judge_at_least(std::abs(f.curl_radius_mm), u, s.min_curl_radius_mm, rule)
                 : Conformity::kConforming;
    note(c, name + " curl radius " + fixed2(f.curl_radius_mm) + " mm (" + with_u(u) + " mm) " +
                relation(c, "is tighter than") + " " + fixed2(s.min_curl_radius_mm) + " mm");
  }
  return v;
}

void check_health(const VerdictInput& in, const VerdictSettings& s, VerdictResult& out,
                  Tally& tally) {
  const FieldCoverage& field = in.field;
  // Too little of the part in the scan is no evidence against it: what the scan shows may all
  // conform, and the rest cannot be judged. UNDECIDED (re-measure, then a manual check), as an
  // unmeasured bend; a FAIL would scrap good parts whose view is short (issue 32: perfectly made
  // parts seen from one side covered 0.80-0.89 of the model and failed).
  if (field.model_points > 0 && !(field.coverage >= s.min_coverage)) {
    out.reasons.push_back("deformation field coverage " + fixed2(field.coverage) + " < minimum " +
                          fixed2(s.min_coverage) + " (" + field.method +
                          "): the part is not all in the scan (undecided)");
    tally.undecided = true;
  }
  const std::size_t before = out.reasons.size();
  // The residual to the surface, not rms_final (to the nearest model sample): the latter grows
  // with the spacing of the samples, so a large, perfectly made part would fail.
  const double rms = in.fit_rms_residual_mm;
  if (!(rms <= s.max_fit_rms_mm)) {
    out.reasons.push_back("global fit residual rms " + fixed2(rms) + " mm > limit " +
                          fixed2(s.max_fit_rms_mm) + " mm: the analysis cannot be trusted");
  }
  // Two orientations fit within noise: bends may be numbered in reverse, every result may
  // belong to the other orientation.
  if (in.orientation_ambiguous) {
    out.reasons.push_back(
        "ambiguous orientation: two distinct orientations fit within noise (error ratio " +
        fixed2(in.orientation_ambiguity) + "): the analysis cannot be trusted");
  }
  if (out.reasons.size() > before) tally.failed = true;
}

}  // namespace

std::vector<FlangeShapeSummary> flange_shapes(const std::vector<FlangeFit>& flanges) {
  std::vector<FlangeShapeSummary> out;
  out.reserve(flanges.size());
  for (const FlangeFit& f : flanges) {
    const auto larger = [](double a, double b) { return std::abs(a) >= std::abs(b) ? a : b; };
    FlangeShapeSummary summary{f.flange_id,
                               f.shape.measured,
                               f.shape.flatness_max_mm,
                               f.shape.curled,
                               f.shape.curl_radius_mm,
                               f.shape.flatness_uncertainty_mm,
                               f.shape.curl_radius_uncertainty_mm};
    for (const EdgeDeviation& e : f.trim_edges)
      summary.edges.push_back({std::string(edge_kind_name(e.kind)),
                               larger(e.in_plane_min_mm, e.in_plane_max_mm),
                               larger(e.across_min_mm, e.across_max_mm), e.uncertainty_mm,
                               e.in_plane_uncertainty_mm, e.across_uncertainty_mm});
    out.push_back(std::move(summary));
  }
  return out;
}

VerdictResult decide_verdict(const VerdictInput& input, const VerdictSettings& settings) {
  VerdictResult out;
  out.decision_rule = settings.decision_rule;
  Tally tally;
  check_surface(input, settings, out, tally);
  for (const BendMeasurement& bend : input.bends)
    out.bends.push_back(judge_bend(bend, settings, out.reasons, tally));
  for (const FlangeShapeSummary& flange : input.flanges)
    out.flanges.push_back(judge_flange(flange, settings, out.reasons, tally));
  check_health(input, settings, out, tally);
  out.decision = tally.failed      ? PartDecision::kFail
                 : tally.undecided ? PartDecision::kUndecided
                                   : PartDecision::kPass;
  out.pass = out.decision == PartDecision::kPass;
  return out;
}

}  // namespace springscan::analysis
