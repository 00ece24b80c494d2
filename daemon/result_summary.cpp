#include "daemon/result_summary.hpp"

#include "daemon/json_writer.hpp"

namespace springscan::daemon {

namespace {

// A decision by its proto name; absent where nothing was decided (a failed scan, a report from
// before decisions), so a consumer never reads a default as a verdict.
void decision_field(JsonWriter& w, const char* name, v1::Conformity c) {
  if (c != v1::CONFORMITY_UNSPECIFIED) w.field(name, v1::Conformity_Name(c));
}

}  // namespace

std::string result_summary_json(const v1::InspectionReport& report, const PublishedIds& ids) {
  JsonWriter w;
  w.begin_object();
  w.field("schema", "springscan.result.v1");
  w.field("station", ids.station);
  w.field("boot_id", static_cast<std::uint64_t>(ids.boot_id));
  w.field("record", ids.record);
  w.field("result_seq", static_cast<std::uint64_t>(ids.result_seq));
  w.field("created_utc", report.created_utc());
  w.field("job_id", static_cast<std::int64_t>(report.job_id()));
  w.field("part_id", report.input().part_id());
  w.field("result_code", static_cast<std::uint64_t>(report.result_code()));
  w.field("pass", report.verdict().pass());
  const v1::Verdict& verdict = report.verdict();
  if (verdict.decision() != v1::Verdict::DECISION_UNSPECIFIED) {
    w.field("decision", v1::Verdict::Decision_Name(verdict.decision()));
    w.field("decision_rule", v1::VerdictSettings::DecisionRule_Name(verdict.decision_rule()));
  }
  w.begin_array("reasons");
  for (const auto& reason : report.verdict().reasons()) w.element(reason);
  w.end_array();
  w.field("cycle_time_ms", report.cycle_time_ms());
  if (report.has_deviation()) {
    const v1::Deviation& d = report.deviation();
    w.begin_object("deviation");
    w.field("min_mm", d.min());
    w.field("max_mm", d.max());
    w.field("mean_mm", d.mean());
    w.field("rms_mm", d.rms());
    w.field("p95_mm", d.p95());
    w.field("fraction_out_of_tolerance", d.fraction_out_of_tolerance());
    w.field("tolerance_mm", d.tolerance_mm());
    w.field("points", static_cast<std::int64_t>(d.points()));
    w.field("uncertainty_mm", d.uncertainty_mm());
    decision_field(w, "decision", d.decision());
    w.end_object();
  }
  w.begin_array("bends");
  for (const v1::Bend& b : report.bends()) {
    w.begin_object();
    w.field("id", static_cast<std::int64_t>(b.id()));
    w.field("measured", b.measured());
    w.field("nominal_angle_deg", b.nominal_angle_deg());
    w.field("measured_angle_deg", b.measured_angle_deg());
    w.field("springback_deg", b.springback_deg());
    w.field("angle_tolerance_deg", b.angle_tolerance_deg());
    w.field("pass", b.pass());
    w.field("springback_uncertainty_deg", b.springback_uncertainty_deg());
    w.field("angle_uncertainty_deg", b.angle_uncertainty_deg());
    decision_field(w, "decision", b.decision());
    if (b.angle_along_bend_size() > 0) w.field("angle_spread_deg", b.angle_spread_deg());
    if (b.has_measured_radius_mm()) w.field("measured_radius_mm", b.measured_radius_mm());
    if (!b.status().empty()) w.field("status", b.status());
    w.end_object();
  }
  w.end_array();
  // The flange shape (docs/springback.md "Beyond rigid flanges"): curl and twist only where
  // measured, as in the report.
  w.begin_array("flanges");
  for (const v1::Segment& seg : report.segments()) {
    w.begin_object();
    w.field("id", static_cast<std::int64_t>(seg.id()));
    w.field("flatness_mm", seg.flatness_mm());
    w.field("flatness_rms_mm", seg.flatness_rms_mm());
    w.field("flatness_uncertainty_mm", seg.flatness_uncertainty_mm());
    if (seg.has_curl_radius_mm()) {
      w.field("curl_radius_mm", seg.curl_radius_mm());
      w.field("curl_radius_uncertainty_mm", seg.curl_radius_uncertainty_mm());
    }
    decision_field(w, "shape_decision", seg.shape_decision());
    if (seg.has_twist_deg_per_100mm()) w.field("twist_deg_per_100mm", seg.twist_deg_per_100mm());
    w.end_object();
  }
  w.end_array();
  // The check part's comparison (docs/calibration.md): only in a check part's result.
  if (report.has_check()) {
    w.begin_object("check");
    w.field("calibration_drift", report.check().drift());
    w.begin_array("items");
    for (const v1::CheckItem& item : report.check().items()) {
      w.begin_object();
      w.field("characteristic", item.characteristic());
      w.field("reference", item.reference());
      w.field("limit", item.limit());
      if (item.has_measured()) w.field("measured", item.measured());
      w.field("beyond", item.beyond());
      w.end_object();
    }
    w.end_array();
    w.end_object();
  }
  w.end_object();
  return w.take();
}

}  // namespace springscan::daemon
