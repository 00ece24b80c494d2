// The inspection verdict (verdict.hpp): one reason per failing rule, with its numbers.
#include "analysis/inspection/verdict.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

namespace springscan::analysis {
namespace {

std::string fixed2(double x) {
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, "%.2f", x);
  return buffer;
}

// Share of |d| beyond the limit; a fixed serial order, so the figure is reproducible.
double fraction_beyond(std::span<const double> d, double limit) {
  if (d.empty()) return 0.0;
  const auto out =
      std::count_if(d.begin(), d.end(), [limit](double v) { return std::abs(v) > limit; });
  return static_cast<double>(out) / static_cast<double>(d.size());
}

void check_surface(const VerdictInput& in, const VerdictSettings& s, VerdictResult& out) {
  out.tolerance_mm = s.tolerance_mm;
  out.fraction_out_of_tolerance = fraction_beyond(in.signed_distance_mm, s.tolerance_mm);
  const DeviationStatistics& d = in.deviation;
  if (d.points == 0) {
    out.reasons.push_back("no surface deviation was computed (0 scan points compared)");
    return;
  }
  const bool p95 = s.deviation_statistic == DeviationStatistic::kP95;
  const double value = p95 ? d.p95_mm : std::max(std::abs(d.min_mm), std::abs(d.max_mm));
  // NaN fails too: a statistic that cannot be compared is not a pass.
  if (!(value <= s.tolerance_mm)) {
    out.reasons.push_back(std::string(p95 ? "p95" : "max") + " |deviation| " + fixed2(value) +
                          " mm > tolerance " + fixed2(s.tolerance_mm) + " mm");
  }
}

void check_bends(const VerdictInput& in, const VerdictSettings& s, VerdictResult& out) {
  for (const BendMeasurement& bend : in.bends) {
    const auto own = s.angle_tolerance_deg_by_bend.find(bend.bend_id);
    const double tolerance =
        own != s.angle_tolerance_deg_by_bend.end() ? own->second : s.angle_tolerance_deg;
    // The one place a bend passes: the report and the PLC's bend flags copy this. A closed hem
    // (not measurable) is not judged and raises no failure flag.
    const bool pass =
        bend.measurable ? bend.measured && std::abs(bend.springback_deg) <= tolerance : true;
    out.bends.push_back({bend.bend_id, tolerance, pass});
    const std::string name = "bend " + std::to_string(bend.bend_id);
    if (!bend.measured) {
      // A closed hem is listed as not measurable; it never fails the part by itself.
      if (s.fail_unmeasured_bends && bend.measurable) {
        out.reasons.push_back(bend.status.empty() ? name + " not measured" : bend.status);
      }
      continue;
    }
    if (!pass) {
      out.reasons.push_back(name + " springback " + fixed2(bend.springback_deg) + " deg (nominal " +
                            fixed2(bend.nominal_angle_deg) + ", measured " +
                            fixed2(bend.measured_angle_deg) + ") exceeds tolerance " +
                            fixed2(tolerance) + " deg");
    }
  }
}

void check_shape(const VerdictInput& in, const VerdictSettings& s, VerdictResult& out) {
  if (s.max_angle_spread_deg > 0.0) {
    for (const BendMeasurement& bend : in.bends) {
      if (bend.stations.empty() || bend.angle_spread_deg <= s.max_angle_spread_deg) continue;
      out.reasons.push_back(
          "bend " + std::to_string(bend.bend_id) + " angle spread along the bend " +
          fixed2(bend.angle_spread_deg) + " deg (" + fixed2(bend.angle_min_deg) + " to " +
          fixed2(bend.angle_max_deg) + ") exceeds " + fixed2(s.max_angle_spread_deg) + " deg");
    }
  }
  for (const FlangeShapeSummary& f : in.flanges) {
    if (!f.measured) continue;
    const std::string name = "flange " + std::to_string(f.flange_id);
    for (const EdgeSummary& e : f.edges) {
      if (s.max_edge_deviation_mm > 0.0 &&
          !(std::max(std::abs(e.in_plane_mm), std::abs(e.across_mm)) <= s.max_edge_deviation_mm)) {
        out.reasons.push_back(name + " " + e.kind + " edge off by " + fixed2(e.in_plane_mm) +
                              " mm in-plane, " + fixed2(e.across_mm) + " mm across (limit " +
                              fixed2(s.max_edge_deviation_mm) + " mm)");
      }
    }
    if (s.max_flatness_mm > 0.0 && !(f.flatness_mm <= s.max_flatness_mm)) {
      out.reasons.push_back(name + " flatness " + fixed2(f.flatness_mm) + " mm exceeds " +
                            fixed2(s.max_flatness_mm) + " mm");
    }
    if (s.min_curl_radius_mm > 0.0 && f.curled &&
        !(std::abs(f.curl_radius_mm) >= s.min_curl_radius_mm)) {
      out.reasons.push_back(name + " curl radius " + fixed2(f.curl_radius_mm) +
                            " mm is tighter than " + fixed2(s.min_curl_radius_mm) + " mm");
    }
  }
}

void check_health(const VerdictInput& in, const VerdictSettings& s, VerdictResult& out) {
  const FieldCoverage& field = in.field;
  if (field.model_points > 0 && !(field.coverage >= s.min_coverage)) {
    out.reasons.push_back("deformation field coverage " + fixed2(field.coverage) + " < minimum " +
                          fixed2(s.min_coverage) + " (" + field.method + ")");
  }
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
}

}  // namespace

std::vector<FlangeShapeSummary> flange_shapes(const std::vector<FlangeFit>& flanges) {
  std::vector<FlangeShapeSummary> out;
  out.reserve(flanges.size());
  for (const FlangeFit& f : flanges) {
    const auto larger = [](double a, double b) { return std::abs(a) >= std::abs(b) ? a : b; };
    FlangeShapeSummary summary{f.flange_id, f.shape.measured, f.shape.flatness_max_mm,
                               f.shape.curled, f.shape.curl_radius_mm};
    for (const EdgeDeviation& e : f.trim_edges)
      summary.edges.push_back({std::string(edge_kind_name(e.kind)),
                               larger(e.in_plane_min_mm, e.in_plane_max_mm),
                               larger(e.across_min_mm, e.across_max_mm)});
    out.push_back(std::move(summary));
  }
  return out;
}

VerdictResult decide_verdict(const VerdictInput& input, const VerdictSettings& settings) {
  VerdictResult out;
  check_surface(input, settings, out);
  check_bends(input, settings, out);
  check_shape(input, settings, out);
  check_health(input, settings, out);
  out.pass = out.reasons.empty();
  return out;
}

}  // namespace springscan::analysis
