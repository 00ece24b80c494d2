#include "daemon/page_text.hpp"

#include <algorithm>
#include <cstdio>

#include "daemon/json_writer.hpp"

namespace springscan::daemon {

namespace {

std::string local_time_text(std::time_t t) {
  std::tm tm{};
  localtime_r(&t, &tm);
  char text[32];
  std::strftime(text, sizeof text, "%Y-%m-%d %H:%M:%S", &tm);
  return text;
}

const char* error_text(regs::ErrorCode code) {
  switch (code) {
    case regs::ErrorCode::kNone:
      return "";
    case regs::ErrorCode::kScanFailed:
      return "scan failed: check the scanner cable and power, then reset the error at the PLC";
    case regs::ErrorCode::kAnalysisFailed:
      return "analysis failed (too few points, no fit): check the part and its PART_ID";
    case regs::ErrorCode::kPartModelFailed:
      return "the part's CAD model or settings could not be loaded: check the config";
    case regs::ErrorCode::kReportWriteFailed:
      return "the report could not be written (disk space, permissions of report_dir): the "
             "result is not valid";
    case regs::ErrorCode::kTriggerNotReleased:
      return "the PLC did not drop TRIGGER after TRIG_ACK: check the PLC handshake";
    case regs::ErrorCode::kPlcCommLost:
      return "PLC heartbeat lost: check the PLC and the network";
    case regs::ErrorCode::kInternal:
      return "internal error: see the journal (journalctl -u springscand)";
  }
  return "unknown error";
}

const char* detail_text(regs::ErrorDetail detail) {
  switch (detail) {
    case regs::ErrorDetail::kNone:
      return "";
    case regs::ErrorDetail::kDeviceGone:
      return "scanner unplugged or not found";
    case regs::ErrorDetail::kTimeout:
      return "scanner stopped answering";
    case regs::ErrorDetail::kCorruptData:
      return "corrupt data from the scanner";
    case regs::ErrorDetail::kCancelled:
      return "scan cancelled";
    case regs::ErrorDetail::kStalledEndpoint:
      return "USB endpoint stalled";
    case regs::ErrorDetail::kSequenceGap:
      return "scan data lost";
    case regs::ErrorDetail::kProtocolError:
      return "scanner broke the protocol";
    case regs::ErrorDetail::kDeviceFault:
      return "the scanner reported a fault";
    case regs::ErrorDetail::kOther:
      return "other cause: see the journal";
    case regs::ErrorDetail::kDatumNotMeasurable:
      return "a datum could not be measured: check the part's seat in the fixture";
  }
  return "";
}

void write_result_row(JsonWriter& w, const PageResult& r) {
  w.field("record", r.record);
  w.field("seq", static_cast<std::uint64_t>(r.report.result_seq()));
  w.field("job_id", static_cast<std::uint64_t>(r.report.job_id()));
  w.field("part_id", r.report.input().part_id());
  w.field("time", r.created != 0 ? local_time_text(r.created) : r.report.created_utc());
  w.field("verdict", page_verdict(r.report));
  w.field("result_code", static_cast<std::uint64_t>(r.report.result_code()));
  w.field("report", record_url(r.record, "report.html"));
}

void write_bends(JsonWriter& w, const v1::InspectionReport& report) {
  w.begin_array("bends");
  for (const v1::Bend& b : report.bends()) {
    w.begin_object();
    w.field("id", static_cast<std::int64_t>(b.id()));
    w.field("measured", b.measured());
    w.field("nominal_deg", b.nominal_angle_deg());
    w.field("measured_deg", b.measured_angle_deg());
    w.field("springback_deg", b.springback_deg());
    w.field("tolerance_deg", b.angle_tolerance_deg());
    w.field("pass", b.pass());
    w.field("springback_uncertainty_deg", b.springback_uncertainty_deg());
    w.field("decision", v1::Conformity_Name(b.decision()));
    w.field("status", b.status());
    w.end_object();
  }
  w.end_array();
}

void write_last(JsonWriter& w, const PageResult& r) {
  w.begin_object("last");
  write_result_row(w, r);
  // A failed scan has no cloud, so its report.html has no map (report_html.cpp).
  if (r.report.deviation().points() > 0) w.field("picture", record_url(r.record, "deviation.svg"));
  w.field("cycle_time_ms", r.report.cycle_time_ms());
  w.begin_array("reasons");
  for (const std::string& reason : r.report.verdict().reasons()) w.element(reason);
  w.end_array();
  const v1::Deviation& d = r.report.deviation();
  w.begin_object("deviation");
  w.field("rms_mm", d.rms());
  w.field("p95_mm", d.p95());
  w.field("min_mm", d.min());
  w.field("max_mm", d.max());
  w.field("tolerance_mm", d.tolerance_mm());
  w.field("uncertainty_mm", d.uncertainty_mm());
  w.field("color_scale_mm", d.color_scale_mm());
  w.end_object();
  write_bends(w, r.report);
  w.end_object();
}

void write_status(JsonWriter& w, const PageView& view) {
  const PageStatus& s = view.status;
  w.field("state", page_state(s.state));
  w.field("ready", s.ready);
  w.field("scanner_online", s.scanner_online);
  w.field("plc_comm_lost", s.plc_comm_lost);
  w.field("calibration_drift", s.calibration_drift);
  w.field("error_code", static_cast<std::uint64_t>(s.error_code));
  w.field("error_detail", static_cast<std::uint64_t>(s.error_detail));
  std::string fault = fault_text(s.error_code, s.error_detail);
  // The failed job's own words (the runner wrote them into its report's reasons).
  const bool job_failed = s.error_code == regs::ErrorCode::kScanFailed ||
                          s.error_code == regs::ErrorCode::kAnalysisFailed ||
                          s.error_code == regs::ErrorCode::kPartModelFailed;
  if (job_failed && !view.recent->empty() &&
      std::string(page_verdict(view.recent->front().report)) == "NO RESULT" &&
      view.recent->front().report.verdict().reasons_size() > 0) {
    fault += " (" + view.recent->front().report.verdict().reasons(0) + ")";
  }
  w.field("fault", fault);
}

}  // namespace

void ShiftCounts::count(const v1::InspectionReport& report, int sign) {
  parts += sign;
  const std::string verdict = page_verdict(report);
  if (verdict == "PASS") {
    pass += sign;
  } else if (verdict == "FAIL") {
    fail += sign;
  } else if (verdict == "UNDECIDED") {
    undecided += sign;
  } else {
    no_result += sign;
  }
}

const char* page_verdict(const v1::InspectionReport& report) {
  switch (static_cast<regs::ResultCode>(report.result_code())) {
    case regs::ResultCode::kNoData:
    case regs::ResultCode::kScanFailed:
    case regs::ResultCode::kAnalysisFailed:
      return "NO RESULT";
    case regs::ResultCode::kUndecided:
      return "UNDECIDED";
    default:
      // The runner sets RESULT_CODE 0 only with verdict.pass; a report that `springscan analyze`
      // wrote has no RESULT_CODE (0), and then the verdict alone decides.
      if (static_cast<regs::ResultCode>(report.result_code()) == regs::ResultCode::kOk &&
          report.verdict().pass())
        return "PASS";
      return report.verdict().decision() == v1::Verdict::UNDECIDED ? "UNDECIDED" : "FAIL";
  }
}

const char* page_state(regs::State state) {
  switch (state) {
    case regs::State::kStopped:
      return "starting";
    case regs::State::kIdle:
      return "idle";
    case regs::State::kAcquiring:
      return "scanning";
    case regs::State::kAnalyzing:
      return "analysing";
    case regs::State::kDone:
      return "done";
    case regs::State::kFault:
      return "fault";
  }
  return "unknown";
}

std::string fault_text(regs::ErrorCode code, regs::ErrorDetail detail) {
  if (code == regs::ErrorCode::kNone) return "";
  std::string text = "ERROR " + std::to_string(static_cast<int>(code)) + ": " + error_text(code);
  const std::string why = detail_text(detail);
  if (!why.empty()) text += " - " + why;
  return text;
}

v1::InspectionReport page_fields(const v1::InspectionReport& full) {
  v1::InspectionReport r;
  r.set_station(full.station());
  r.set_created_utc(full.created_utc());
  r.set_job_id(full.job_id());
  r.set_result_seq(full.result_seq());
  r.set_result_code(full.result_code());
  r.set_cycle_time_ms(full.cycle_time_ms());
  r.mutable_input()->set_part_id(full.input().part_id());
  *r.mutable_verdict() = full.verdict();
  *r.mutable_deviation() = full.deviation();
  for (const v1::Bend& b : full.bends()) {
    v1::Bend* bend = r.add_bends();
    bend->set_id(b.id());
    bend->set_nominal_angle_deg(b.nominal_angle_deg());
    bend->set_measured_angle_deg(b.measured_angle_deg());
    bend->set_springback_deg(b.springback_deg());
    bend->set_angle_tolerance_deg(b.angle_tolerance_deg());
    bend->set_pass(b.pass());
    bend->set_decision(b.decision());
    bend->set_springback_uncertainty_deg(b.springback_uncertainty_deg());
    bend->set_measured(b.measured());
    bend->set_status(b.status());
  }
  return r;
}

std::time_t parse_created_utc(const std::string& text) {
  std::tm tm{};
  const char* end = strptime(text.c_str(), "%Y-%m-%dT%H:%M:%SZ", &tm);
  return end != nullptr && *end == '\0' ? timegm(&tm) : 0;
}

std::time_t shift_start(std::time_t now, const std::vector<int>& starts_min) {
  std::time_t best = 0;
  for (const int minutes : starts_min) {
    for (int days_back = 0; days_back <= 1; ++days_back) {
      std::tm tm{};
      localtime_r(&now, &tm);
      tm.tm_mday -= days_back;
      tm.tm_hour = minutes / 60;
      tm.tm_min = minutes % 60;
      tm.tm_sec = 0;
      tm.tm_isdst = -1;  // mktime decides, so a shift start across a DST change stays local
      const std::time_t start = std::mktime(&tm);
      if (start <= now) {
        best = std::max(best, start);
        break;
      }
    }
  }
  return best;
}

std::string record_url(std::uint64_t record, const char* file) {
  char name[64];
  std::snprintf(name, sizeof name, "reports/r%012llu/%s", static_cast<unsigned long long>(record),
                file);
  return name;
}

std::string deviation_svg_from_report_html(const std::string& html) {
  // report/report_html.cpp: <section id='deviation'> holds four <figure class='view'><svg ...>
  // (top, front, side, isometric; report/figures.cpp deviation_views_html). The isometric one is
  // the last; the page shows it as the report store drew it, without drawing it again.
  const std::size_t section = html.find("<section id='deviation'>");
  if (section == std::string::npos) return "";
  const std::size_t section_end = html.find("</section>", section);
  const std::size_t figure = html.rfind("<figure class='view'>", section_end);
  if (figure == std::string::npos || figure < section) return "";
  const std::size_t svg = html.find("<svg", figure);
  const std::size_t svg_end = html.find("</svg>", svg);
  if (svg == std::string::npos || svg_end == std::string::npos || svg_end > section_end) return "";
  // Inline SVG in HTML needs no namespace; a document of its own does.
  return "<svg xmlns='http://www.w3.org/2000/svg'" + html.substr(svg + 4, svg_end + 6 - svg - 4);
}

std::string page_snapshot_json(const PageView& view) {
  JsonWriter w;
  w.begin_object();
  w.field("schema", "springscan.page.v1");
  w.field("station", view.station);
  write_status(w, view);
  if (!view.recent->empty()) write_last(w, view.recent->front());
  w.begin_array("recent");
  for (const PageResult& r : *view.recent) {
    w.begin_object();
    write_result_row(w, r);
    w.end_object();
  }
  w.end_array();
  w.begin_object("shift");
  w.field("start", view.shift_start != 0 ? local_time_text(view.shift_start) : std::string());
  w.field("parts", static_cast<std::int64_t>(view.shift.parts));
  w.field("pass", static_cast<std::int64_t>(view.shift.pass));
  w.field("fail", static_cast<std::int64_t>(view.shift.fail));
  w.field("undecided", static_cast<std::int64_t>(view.shift.undecided));
  w.field("no_result", static_cast<std::int64_t>(view.shift.no_result));
  // Yield over the results that judged the part: a failed scan says nothing about the part; an
  // undecided one was measured but not proven good.
  const int judged = view.shift.pass + view.shift.fail + view.shift.undecided;
  if (judged > 0) w.field("yield_pct", 100.0 * view.shift.pass / judged);
  w.end_object();
  w.end_object();
  return w.take();
}

}  // namespace springscan::daemon
