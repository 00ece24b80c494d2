#pragma once
// What the operator page says (docs/operator-page.md): pure functions from the station's
// status and stored reports to the JSON snapshot the page renders, the shift's bounds, and the
// deviation picture taken from a stored report.html. No threads, no sockets: page_feed.cpp
// calls them, tests call them directly.

#include <cstdint>
#include <ctime>
#include <deque>
#include <string>
#include <vector>

#include "daemon/register_map.hpp"
#include "proto/springscan.pb.h"

namespace springscan::daemon {

/// One result as the page lists it.
struct PageResult {
  std::uint64_t record = 0;
  v1::InspectionReport report;  ///< the fields the page shows (page_fields), not the bulk
  std::time_t created = 0;      ///< report.created_utc as a time (0: unknown)
};

/// The station state the page shows, copied from the MachineStatus on every change.
struct PageStatus {
  regs::State state = regs::State::kStopped;
  regs::ErrorCode error_code = regs::ErrorCode::kNone;
  regs::ErrorDetail error_detail = regs::ErrorDetail::kNone;
  bool ready = false;
  bool scanner_online = false;
  bool plc_comm_lost = false;
  bool calibration_drift = false;  ///< the check part's latch (CALIBRATION_DRIFT)
  bool operator==(const PageStatus&) const = default;
};

/// The shift's results by verdict.
struct ShiftCounts {
  int parts = 0;      ///< every result
  int pass = 0;       ///< PASS
  int fail = 0;       ///< FAIL
  int undecided = 0;  ///< UNDECIDED: within U of a limit; re-measured, then checked by hand
  int no_result = 0;  ///< the scan or the analysis failed: no verdict on the part
  /// Adds (sign 1) or removes (-1) a result.
  void count(const v1::InspectionReport& report, int sign);
};

/// Everything one snapshot shows.
struct PageView {
  std::string station;
  PageStatus status;
  const std::deque<PageResult>* recent = nullptr;  ///< newest first; not owned
  std::time_t shift_start = 0;
  ShiftCounts shift;
};

/// The page's word for a result: PASS (RESULT_CODE 0 and verdict.pass), UNDECIDED (RESULT_CODE
/// 6, or verdict.decision UNDECIDED), FAIL, or NO RESULT (RESULT_CODE 2, 3, 4: nothing was
/// measured).
const char* page_verdict(const v1::InspectionReport& report);
/// The page's word for a state: starting, idle, scanning, analysing, done or fault.
const char* page_state(regs::State state);
/// What a FAULT means for the operator: ERROR_CODE and ERROR_DETAIL in words
/// (docs/modbus-register-map.md "Error codes").
std::string fault_text(regs::ErrorCode code, regs::ErrorDetail detail);
/// The page's copy of a stored report: ids, verdict, deviation statistics, bend table.
v1::InspectionReport page_fields(const v1::InspectionReport& full);
/// report.created_utc ("2026-12-06T22:10:00Z") as a time; 0 when it does not parse.
std::time_t parse_created_utc(const std::string& text);
/// The start of the shift `now` lies in: the latest of the local times of day `starts_min`
/// (minutes after midnight) not after `now`; 0 when `starts_min` is empty.
std::time_t shift_start(std::time_t now, const std::vector<int>& starts_min);
/// "reports/r000000000042/report.html": the URL of a file of a record, relative to the page.
std::string record_url(std::uint64_t record, const char* file);
/// The deviation colour map (isometric view) of a report.html the report store wrote, as a
/// standalone SVG document; empty when the page has none (a failed scan).
std::string deviation_svg_from_report_html(const std::string& html);
/// The snapshot the event stream sends: one line of JSON (docs/operator-page.md "Snapshot").
std::string page_snapshot_json(const PageView& view);

}  // namespace springscan::daemon
