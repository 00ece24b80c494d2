#include "daemon/job_runner.hpp"

#include <sys/eventfd.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <ctime>
#include <stdexcept>

#include "report/check_part.hpp"
#include "report/inspection_files.hpp"

namespace springscan::daemon {

namespace {

std::string job_name(const RunnerJob& job) {
  return "job " + std::to_string(job.request.job_id) + " part " +
         std::to_string(job.request.part_id) + " (result seq " +
         std::to_string(regs::result_seq_from_record(job.record)) + ")";
}

// A check part's figure for the log: deg and mm to a thousandth, as the references are set.
std::string decimals(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.3f", value);
  return text;
}

// What the operator should do, per ERROR_CODE (docs/modbus-register-map.md, "Error codes").
std::string operator_hint(regs::ErrorCode code) {
  switch (code) {
    case regs::ErrorCode::kScanFailed:
      return ". The station is in FAULT (ERROR_CODE 2). Check the scanner's cable and power and "
             "that the part is in place, then set ERROR_RESET (coil 3) from the PLC.";
    case regs::ErrorCode::kPartModelFailed:
      return ". The station is in FAULT (ERROR_CODE 4). Check the part's cad_file and settings "
             "in the config, then set ERROR_RESET (coil 3).";
    case regs::ErrorCode::kInternal:
      return ". The station is in FAULT (ERROR_CODE 9): this is a bug; keep this log, then set "
             "ERROR_RESET (coil 3).";
    default:
      return ". The station is in FAULT (ERROR_CODE 3). Check that the right part (PART_ID) is "
             "on the fixture and clean, then set ERROR_RESET (coil 3).";
  }
}

}  // namespace

PlcError plc_error_for_scan(analysis::ErrorCode code) {
  using analysis::ErrorCode;
  using D = regs::ErrorDetail;
  constexpr auto kScan = regs::ErrorCode::kScanFailed;
  switch (code) {
    case ErrorCode::kDeviceGone:
    case ErrorCode::kNotFound:  // not there when the scan began: as good as unplugged
      return {kScan, D::kDeviceGone};
    case ErrorCode::kTimeout:
      return {kScan, D::kTimeout};
    case ErrorCode::kBadCrc:
      return {kScan, D::kCorruptData};
    case ErrorCode::kCancelled:
      return {kScan, D::kCancelled};
    case ErrorCode::kStalledEndpoint:
      return {kScan, D::kStalledEndpoint};
    case ErrorCode::kSequenceGap:
      return {kScan, D::kSequenceGap};
    case ErrorCode::kProtocolError:
      return {kScan, D::kProtocolError};
    case ErrorCode::kDeviceFault:
      return {kScan, D::kDeviceFault};
    case ErrorCode::kInternal:
      return {regs::ErrorCode::kInternal, D::kOther};
    case ErrorCode::kOsError:
    case ErrorCode::kInvalidInput:
    case ErrorCode::kIoError:
    case ErrorCode::kCorruption:
    case ErrorCode::kInvalidSettings:  // e.g. the configured kind is not the device's
    case ErrorCode::kAnalysisFailed:
      return {kScan, D::kOther};
  }
  return {kScan, D::kOther};
}

PlcError plc_error_for_analysis(analysis::ErrorCode code) {
  using analysis::ErrorCode;
  using D = regs::ErrorDetail;
  switch (code) {
    // The scan is in memory: the files an analysis reads are the part's CAD model (and its
    // cache), and its settings come from the part catalogue.
    case ErrorCode::kNotFound:
    case ErrorCode::kIoError:
    case ErrorCode::kCorruption:
    case ErrorCode::kInvalidSettings:
      return {regs::ErrorCode::kPartModelFailed, D::kOther};
    case ErrorCode::kCancelled:
      return {regs::ErrorCode::kAnalysisFailed, D::kCancelled};
    case ErrorCode::kInternal:
      return {regs::ErrorCode::kInternal, D::kOther};
    case ErrorCode::kInvalidInput:
    case ErrorCode::kAnalysisFailed:
    case ErrorCode::kDeviceGone:
    case ErrorCode::kTimeout:
    case ErrorCode::kStalledEndpoint:
    case ErrorCode::kBadCrc:
    case ErrorCode::kSequenceGap:
    case ErrorCode::kProtocolError:
    case ErrorCode::kDeviceFault:
    case ErrorCode::kOsError:
      return {regs::ErrorCode::kAnalysisFailed, D::kOther};
  }
  return {regs::ErrorCode::kAnalysisFailed, D::kOther};
}

std::optional<PlcError> plc_error_for_alignment(const v1::Alignment& alignment) {
  // A report without an alignment section (achieved unset) names no datum: not a failure.
  if (alignment.achieved() || alignment.failed_datum().empty()) return std::nullopt;
  return PlcError{regs::ErrorCode::kAnalysisFailed, regs::ErrorDetail::kDatumNotMeasurable};
}

JobRunner::JobRunner(drivers::Scanner& scanner, AnalyzeFn analyze, ReportStore& store, Log& log,
                     RunnerSettings settings)
    : scanner_(scanner),
      analyze_(std::move(analyze)),
      store_(store),
      log_(log),
      settings_(std::move(settings)),
      wake_fd_(eventfd(0, EFD_NONBLOCK | EFD_CLOEXEC)) {
  if (wake_fd_ < 0) throw std::runtime_error("JobRunner: eventfd failed");
  thread_ = std::thread([this] { worker(); });
}

JobRunner::~JobRunner() {
  {
    std::lock_guard lock(mutex_);
    stop_ = true;
  }
  cancel_ = true;
  wake_worker_.notify_all();
  thread_.join();
  close(wake_fd_);
}

void JobRunner::start(const RunnerJob& job) {
  {
    std::lock_guard lock(mutex_);
    pending_ = job;
  }
  progress_pct_ = 0;
  wake_worker_.notify_all();
}

std::vector<RunnerEvent> JobRunner::take_events() {
  std::uint64_t count = 0;
  [[maybe_unused]] const ssize_t n = read(wake_fd_, &count, sizeof count);
  std::lock_guard lock(mutex_);
  std::vector<RunnerEvent> out(std::make_move_iterator(events_.begin()),
                               std::make_move_iterator(events_.end()));
  events_.clear();
  return out;
}

void JobRunner::post(RunnerEvent event) {
  {
    std::lock_guard lock(mutex_);
    events_.push_back(std::move(event));
  }
  const std::uint64_t one = 1;
  [[maybe_unused]] const ssize_t n = write(wake_fd_, &one, sizeof one);
}

void JobRunner::worker() {
  const auto interval = std::chrono::duration<double>(settings_.probe_interval_s);
  probe_scanner();
  for (;;) {
    std::optional<RunnerJob> job;
    {
      std::unique_lock lock(mutex_);
      wake_worker_.wait_for(lock, interval, [this] { return stop_ || pending_.has_value(); });
      if (stop_) return;
      job.swap(pending_);
    }
    if (job) {
      run(*job);
    } else {
      probe_scanner();
    }
  }
}

void JobRunner::probe_scanner() {
  const bool was_online = online_.load();
  // identify() every time, not only while offline: it takes in the USB events since the last
  // probe (a scanner unplugged, or power-cycled, while the station was idle), reopens the
  // device when it is back, and otherwise answers from the open link without any I/O.
  // online() alone would go on reporting the state of the last scan.
  const auto info = scanner_.identify();
  // Present and open is online even when identify() refuses the device (another kind than
  // configured), as before: a trigger then fails with the reason (ERROR_DETAIL 9) instead of
  // the station sitting offline; the reason is logged here too.
  const bool now_online = scanner_.online();
  if (now_online && !was_online && info) {
    log_.info("scanner online: " + info->kind + " " + info->model + " serial " + info->serial +
              " firmware " + info->firmware);
  } else if (now_online && !was_online) {
    log_.warning("scanner present but not usable: " + info.message());
  }
  if (was_online && !now_online) {
    log_.warning(
        "scanner went offline: SCANNER_ONLINE is 0 and triggers are refused. Check "
        "the scanner's USB cable and power; it is reopened automatically.");
  }
  online_ = now_online;
}

void JobRunner::run(const RunnerJob& job) {
  const std::string name = job_name(job);
  const auto started = Clock::now();
  cancel_ = false;
  log_.info(name + ": scan started");
  auto scan = scanner_.scan([this](double done) {
    progress_pct_ = static_cast<std::uint16_t>(std::clamp(done, 0.0, 1.0) * 100.0 + 0.5);
    return !cancel_.load();
  });
  online_ = scanner_.online();
  v1::InspectionReport report;
  if (!scan) {
    const PlcError plc = plc_error_for_scan(scan.code());
    JobEnd end{regs::ResultCode::kScanFailed, false, false, plc.code, plc.detail};
    log_.error(name + ": SCAN FAILED (" + analysis::to_string(scan.code()) + ", ERROR_DETAIL " +
               std::to_string(static_cast<int>(plc.detail)) + "): " + scan.message() +
               operator_hint(plc.code));
    report.mutable_verdict()->add_reasons("scan failed: " + scan.message());
    post(finish(job, report_only(std::move(report)), end));
    return;
  }
  const auto scanned = Clock::now();
  log_.info(name + ": scanned " + std::to_string(scan->size()) + " points in " +
            std::to_string(std::chrono::duration<double>(scanned - started).count()) +
            " s; analysing");
  if (const std::string note = scanner_.last_scan_note(); !note.empty())
    log_.warning(name + ": " + note);
  post(RunnerEvent{RunnerEvent::Kind::kAcquired, job.record, {}, {}, {}, {}});
  auto outcome = analyze_(job.request.part_id, *scan);
  if (!outcome) {
    const PlcError plc = plc_error_for_analysis(outcome.code());
    JobEnd end{regs::ResultCode::kAnalysisFailed, false, false, plc.code, plc.detail};
    log_.error(name + ": ANALYSIS FAILED (" + analysis::to_string(outcome.code()) +
               "): " + outcome.message() + operator_hint(plc.code));
    report.mutable_verdict()->add_reasons("analysis failed: " + outcome.message());
    report.mutable_input()->set_scan_points(static_cast<std::int64_t>(scan->size()));
    post(finish(job, report_only(std::move(report)), end));
    return;
  }
  const v1::Verdict& decided = outcome->report.verdict();
  const bool pass = decided.pass();
  const bool undecided = decided.decision() == v1::Verdict::UNDECIDED;
  const auto code = pass                                       ? regs::ResultCode::kOk
                    : outcome->report.global_fit().ambiguous() ? regs::ResultCode::kAmbiguous
                    : undecided                                ? regs::ResultCode::kUndecided
                                                               : regs::ResultCode::kFormNok;
  JobEnd end{code, pass, false, regs::ErrorCode::kNone, regs::ErrorDetail::kNone};
  std::string verdict = pass ? "PASS" : undecided ? "UNDECIDED" : "FAIL";
  for (const auto& reason : outcome->report.verdict().reasons()) verdict += "; " + reason;
  // No datum frame: the result stands (its verdict never PASS), the station faults with why.
  if (const auto plc = plc_error_for_alignment(outcome->report.alignment())) {
    end.error_code = plc->code;
    end.error_detail = plc->detail;
    log_.error(name + ": " + verdict + " (ERROR_DETAIL " +
               std::to_string(static_cast<int>(plc->detail)) + ")" + operator_hint(plc->code));
  } else {
    log_.info(name + ": " + verdict);
  }
  std::optional<v1::CheckResult> check = check_part(job, outcome->report);
  RunnerEvent event = finish(job, std::move(*outcome), end);
  // Only a persisted comparison changes CALIBRATION_DRIFT: its report is the evidence.
  if (event.end.persisted) event.check = std::move(check);
  post(std::move(event));
}

std::optional<v1::CheckResult> JobRunner::check_part(const RunnerJob& job,
                                                     v1::InspectionReport& report) {
  const auto& config = settings_.check_part;
  if (!config || config->part_id() != job.request.part_id) return std::nullopt;
  *report.mutable_check() = springscan::report::check_part(report, *config);
  const v1::CheckResult& check = report.check();
  std::string items;
  for (const v1::CheckItem& item : check.items()) {
    if (!item.beyond()) continue;
    items += "; " + item.characteristic() + " " +
             (item.has_measured() ? decimals(item.measured()) : std::string("not measured")) +
             " (reference " + decimals(item.reference()) + " +- " + decimals(item.limit()) + ")";
  }
  const std::string text = job_name(job) + ": check part compared with " +
                           std::to_string(check.items_size()) + " references: ";
  if (check.drift()) {
    log_.warning(text + "BEYOND its limits" + items);
  } else {
    log_.info(text + "all within their limits");
  }
  return check;
}

RunnerEvent JobRunner::finish(const RunnerJob& job, analysis::InspectionOutcome outcome,
                              JobEnd end) {
  const std::string name = job_name(job);
  v1::InspectionReport& report = outcome.report;
  report.set_schema("springscan.report.v1");
  report::stamp_report(report);
  report.set_station(settings_.station_name);
  report.set_job_id(job.request.job_id);
  report.set_result_seq(regs::result_seq_from_record(job.record));
  report.set_result_code(static_cast<std::uint32_t>(end.result_code));
  report.mutable_input()->set_part_id(std::to_string(job.request.part_id));
  if (job.request.part_serial != 0)
    report.mutable_input()->set_part_serial(std::to_string(job.request.part_serial));
  if (end.result_code != regs::ResultCode::kOk) report.mutable_verdict()->set_pass(false);
  report.set_cycle_time_ms(
      std::chrono::duration<double, std::milli>(Clock::now() - job.request.trigger_time).count());
  RunnerEvent event{RunnerEvent::Kind::kFinished, job.record, end, {}, {}, {}};
  auto stored = store_.persist(job.record, outcome);
  if (!stored) {
    event.end.persisted = false;
    event.end.error_code = regs::ErrorCode::kReportWriteFailed;
    log_.error(name + ": REPORT NOT WRITTEN: " + stored.message() +
               ". The result is NOT given to the PLC (ERROR_CODE 5). Check free space and "
               "permissions of report_dir, then set ERROR_RESET (coil 3).");
    return event;
  }
  event.end.persisted = true;
  event.report_path = *stored;
  event.block = result_block_from_report(report);
  log_.info(name + ": report written to " + *stored);
  return event;
}

}  // namespace springscan::daemon
