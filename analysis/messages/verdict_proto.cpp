// Proto conversions of the verdict (verdict_proto.hpp).
#include "analysis/messages/verdict_proto.hpp"

#include <cmath>
#include <optional>
#include <string>

namespace springscan::analysis {
namespace {

Error bad(const std::string& field, double value, const std::string& rule) {
  return fail(ErrorCode::kInvalidSettings,
              "settings: " + field + " = " + std::to_string(value) + " (" + rule + ")");
}

// The one range check of each tolerance, wherever the message spells it.
std::optional<Error> check_tolerance_mm(const std::string& field, double mm) {
  if (mm > 0.0 && mm <= 1e6) return std::nullopt;  // NaN fails both
  return bad(field, mm, "0 < mm <= 1e6");
}

std::optional<Error> check_angle_tolerance_deg(const std::string& field, double deg) {
  if (deg > 0.0 && deg <= 180.0) return std::nullopt;
  return bad(field, deg, "0 < deg <= 180");
}

// Shape tolerances: 0 switches the rule off, so 0 is allowed.
std::optional<Error> check_shape_limit(const std::string& field, double value) {
  if (value >= 0.0 && value <= 1e6) return std::nullopt;
  return bad(field, value, "0 (off) to 1e6");
}

v1::VerdictSettings::DecisionRule proto_rule(DecisionRule rule) {
  return rule == DecisionRule::kSimple ? v1::VerdictSettings::SIMPLE
                                       : v1::VerdictSettings::GUARD_BAND;
}

v1::Conformity proto_conformity(Conformity c) {
  switch (c) {
    case Conformity::kConforming:
      return v1::CONFORMING;
    case Conformity::kNonconforming:
      return v1::NONCONFORMING;
    case Conformity::kUndecided:
      return v1::UNDECIDED;
    case Conformity::kNotJudged:
      break;
  }
  return v1::CONFORMITY_UNSPECIFIED;
}

v1::Verdict::Decision proto_decision(PartDecision d) {
  switch (d) {
    case PartDecision::kPass:
      return v1::Verdict::PASS;
    case PartDecision::kFail:
      return v1::Verdict::FAIL;
    case PartDecision::kUndecided:
      break;
  }
  return v1::Verdict::UNDECIDED;
}

}  // namespace

Expected<VerdictSettings> from_proto(const v1::VerdictSettings& m) {
  VerdictSettings s;
  if (m.has_tolerance_mm()) {
    if (auto error = check_tolerance_mm("verdict.tolerance_mm", m.tolerance_mm())) return *error;
    s.tolerance_mm = m.tolerance_mm();
  }
  if (m.has_angle_tolerance_deg()) {
    if (auto error =
            check_angle_tolerance_deg("verdict.angle_tolerance_deg", m.angle_tolerance_deg()))
      return *error;
    s.angle_tolerance_deg = m.angle_tolerance_deg();
  }
  if (m.has_deviation_statistic() && m.deviation_statistic() == v1::VerdictSettings::MAX) {
    s.deviation_statistic = DeviationStatistic::kMax;
  } else if (m.has_deviation_statistic() && m.deviation_statistic() == v1::VerdictSettings::P95) {
    s.deviation_statistic = DeviationStatistic::kP95;
  }
  if (m.has_decision_rule() && m.decision_rule() == v1::VerdictSettings::SIMPLE) {
    s.decision_rule = DecisionRule::kSimple;
  } else if (m.has_decision_rule() && m.decision_rule() == v1::VerdictSettings::GUARD_BAND) {
    s.decision_rule = DecisionRule::kGuardBand;
  }
  if (m.has_min_coverage()) {
    if (!(m.min_coverage() >= 0.0 && m.min_coverage() <= 1.0)) {
      return bad("verdict.min_coverage", m.min_coverage(), "0 to 1");
    }
    s.min_coverage = m.min_coverage();
  }
  if (m.has_max_fit_rms_mm()) {
    if (!(m.max_fit_rms_mm() > 0.0)) {
      return bad("verdict.max_fit_rms_mm", m.max_fit_rms_mm(), "must be > 0");
    }
    s.max_fit_rms_mm = m.max_fit_rms_mm();
  }
  if (m.has_max_angle_spread_deg()) {
    if (auto e = check_shape_limit("verdict.max_angle_spread_deg", m.max_angle_spread_deg()))
      return *e;
    s.max_angle_spread_deg = m.max_angle_spread_deg();
  }
  if (m.has_min_curl_radius_mm()) {
    if (auto e = check_shape_limit("verdict.min_curl_radius_mm", m.min_curl_radius_mm())) return *e;
    s.min_curl_radius_mm = m.min_curl_radius_mm();
  }
  if (m.has_max_flatness_mm()) {
    if (auto e = check_shape_limit("verdict.max_flatness_mm", m.max_flatness_mm())) return *e;
    s.max_flatness_mm = m.max_flatness_mm();
  }
  if (m.has_max_edge_deviation_mm()) {
    if (auto e = check_shape_limit("verdict.max_edge_deviation_mm", m.max_edge_deviation_mm()))
      return *e;
    s.max_edge_deviation_mm = m.max_edge_deviation_mm();
  }
  return s;
}

Expected<VerdictSettings> verdict_settings_from_proto(const v1::AnalysisSettings& m) {
  auto s = from_proto(m.verdict());
  if (!s) return s.error();
  if (m.deviation().has_tolerance_mm() && !m.verdict().has_tolerance_mm()) {
    if (auto error = check_tolerance_mm("deviation.tolerance_mm", m.deviation().tolerance_mm()))
      return *error;
    s->tolerance_mm = m.deviation().tolerance_mm();
  }
  return s;
}

void to_proto(const VerdictSettings& s, v1::VerdictSettings* m) {
  m->set_tolerance_mm(s.tolerance_mm);
  m->set_angle_tolerance_deg(s.angle_tolerance_deg);
  m->set_deviation_statistic(s.deviation_statistic == DeviationStatistic::kMax
                                 ? v1::VerdictSettings::MAX
                                 : v1::VerdictSettings::P95);
  m->set_min_coverage(s.min_coverage);
  m->set_max_fit_rms_mm(s.max_fit_rms_mm);
  m->set_max_angle_spread_deg(s.max_angle_spread_deg);
  m->set_min_curl_radius_mm(s.min_curl_radius_mm);
  m->set_max_flatness_mm(s.max_flatness_mm);
  m->set_max_edge_deviation_mm(s.max_edge_deviation_mm);
  m->set_decision_rule(proto_rule(s.decision_rule));
}

void to_proto(const VerdictResult& verdict, v1::InspectionReport* report) {
  v1::Verdict& out = *report->mutable_verdict();
  out.set_pass(verdict.pass);
  out.set_decision(proto_decision(verdict.decision));
  out.set_decision_rule(proto_rule(verdict.decision_rule));
  out.clear_reasons();
  for (const std::string& reason : verdict.reasons) out.add_reasons(reason);
  v1::Deviation& deviation = *report->mutable_deviation();
  deviation.set_tolerance_mm(verdict.tolerance_mm);
  deviation.set_fraction_out_of_tolerance(verdict.fraction_out_of_tolerance);
  deviation.set_uncertainty_mm(verdict.surface_uncertainty_mm);
  deviation.set_decision(proto_conformity(verdict.surface_decision));
  for (const BendVerdict& decided : verdict.bends) {
    for (v1::Bend& bend : *report->mutable_bends()) {
      if (bend.id() != decided.bend_id) continue;
      bend.set_angle_tolerance_deg(decided.angle_tolerance_deg);
      bend.set_pass(decided.pass);
      bend.set_decision(proto_conformity(decided.decision));
    }
  }
  for (const FlangeVerdict& decided : verdict.flanges) {
    for (v1::Segment& segment : *report->mutable_segments()) {
      if (segment.id() == decided.flange_id)
        segment.set_shape_decision(proto_conformity(decided.shape_decision));
    }
  }
}

}  // namespace springscan::analysis
