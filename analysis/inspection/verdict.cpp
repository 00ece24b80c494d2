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

void check_surface(const v1::InspectionReport& r, const VerdictSettings& s, v1::Verdict& out) {
  const v1::Deviation& d = r.deviation();
  if (d.points() <= 0) {
    out.add_reasons("no surface deviation was computed (0 scan points compared)");
    return;
  }
  const bool p95 = s.deviation_statistic == DeviationStatistic::kP95;
  const double value = p95 ? d.p95() : std::max(std::abs(d.min()), std::abs(d.max()));
  // NaN fails too: a statistic that cannot be compared is not a pass.
  if (!(value <= s.tolerance_mm)) {
    out.add_reasons(std::string(p95 ? "p95" : "max") + " |deviation| " + fixed2(value) +
                    " mm > tolerance " + fixed2(s.tolerance_mm) + " mm");
  }
}

void check_bends(const v1::InspectionReport& r, const VerdictSettings& s, v1::Verdict& out) {
  for (const v1::Bend& bend : r.bends()) {
    const std::string name = "bend " + std::to_string(bend.id());
    if (!bend.measured()) {
      if (s.fail_unmeasured_bends) {
        out.add_reasons(name + " not measured (a flange had too few scan points)");
      }
      continue;
    }
    const double tolerance =
        bend.angle_tolerance_deg() > 0.0 ? bend.angle_tolerance_deg() : s.angle_tolerance_deg;
    if (!(std::abs(bend.springback_deg()) <= tolerance)) {
      out.add_reasons(name + " springback " + fixed2(bend.springback_deg()) + " deg (nominal " +
                      fixed2(bend.nominal_angle_deg()) + ", measured " +
                      fixed2(bend.measured_angle_deg()) + ") exceeds tolerance " +
                      fixed2(tolerance) + " deg");
    }
  }
}

void check_health(const v1::InspectionReport& r, const VerdictSettings& s, v1::Verdict& out) {
  const v1::DeformationField& field = r.deformation_field();
  if (field.model_points() > 0 && !(field.coverage() >= s.min_coverage)) {
    out.add_reasons("deformation field coverage " + fixed2(field.coverage()) + " < minimum " +
                    fixed2(s.min_coverage) + " (" + field.method() + ")");
  }
  // The residual to the surface, not rms_final (to the nearest model sample): the latter grows
  // with the spacing of the samples, so a large, perfectly made part would fail.
  const double rms = r.global_fit().rms_residual();
  if (!(rms <= s.max_fit_rms_mm)) {
    out.add_reasons("global fit residual rms " + fixed2(rms) + " mm > limit " +
                    fixed2(s.max_fit_rms_mm) + " mm: the analysis cannot be trusted");
  }
  // Two orientations fit within noise: bends may be numbered in reverse, every result may
  // belong to the other orientation.
  if (r.global_fit().ambiguous()) {
    out.add_reasons(
        "ambiguous orientation: two distinct orientations fit within noise (error "
        "ratio " +
        fixed2(r.global_fit().orientation_ambiguity()) + "): the analysis cannot be trusted");
  }
}

}  // namespace

v1::Verdict decide_verdict(const v1::InspectionReport& report, const VerdictSettings& settings) {
  v1::Verdict out;
  check_surface(report, settings, out);
  check_bends(report, settings, out);
  check_health(report, settings, out);
  out.set_pass(out.reasons_size() == 0);
  return out;
}

}  // namespace springscan::analysis
