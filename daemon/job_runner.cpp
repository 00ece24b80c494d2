#include "daemon/job_runner.hpp"

#include <sys/eventfd.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <ctime>
#include <stdexcept>

namespace springscan::daemon {

namespace {

std::string utc_now() {
  const std::time_t t = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&t, &tm);
  char text[32];
  std::strftime(text, sizeof text, "%Y-%m-%dT%H:%M:%SZ", &tm);
  return text;
}

std::string job_name(const RunnerJob& job) {
  return "job " + std::to_string(job.request.job_id) + " part " +
         std::to_string(job.request.part_id) + " (result seq " +
         std::to_string(regs::result_seq_from_record(job.record)) + ")";
}

std::string lower(std::string text) {
  std::transform(text.begin(), text.end(), text.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return text;
}

}  // namespace

regs::ErrorDetail classify_scan_error(const std::string& message) {
  const std::string m = lower(message);
  const auto has = [&m](const char* word) { return m.find(word) != std::string::npos; };
  if (has("unplug") || has("no device") || has("disconnect") || has("gone") || has("not found")) {
    return regs::ErrorDetail::kDeviceGone;
  }
  if (has("timeout") || has("timed out")) return regs::ErrorDetail::kTimeout;
  if (has("corrupt") || has("crc") || has("checksum")) return regs::ErrorDetail::kCorruptData;
  if (has("cancel")) return regs::ErrorDetail::kCancelled;
  return regs::ErrorDetail::kOther;
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
  bool now_online = scanner_.online();
  if (!now_online) {
    // identify() opens the device when it has come back (hotplug, replug).
    const auto info = scanner_.identify();
    now_online = info.ok() && scanner_.online();
    if (now_online) {
      log_.info("scanner online: " + info->kind + " " + info->model + " serial " + info->serial +
                " firmware " + info->firmware);
    }
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
    JobEnd end{regs::ResultCode::kScanFailed, false, false, regs::ErrorCode::kScanFailed,
               classify_scan_error(scan.message())};
    log_.error(name + ": SCAN FAILED: " + scan.message() +
               ". The station is in FAULT (ERROR_CODE 2). Check the scanner's cable and power "
               "and that the part is in place, then set ERROR_RESET (coil 3) from the PLC.");
    report.mutable_verdict()->add_reasons("scan failed: " + scan.message());
    post(finish(job, std::move(report), nullptr, end));
    return;
  }
  const auto scanned = Clock::now();
  log_.info(name + ": scanned " + std::to_string(scan->size()) + " points in " +
            std::to_string(std::chrono::duration<double>(scanned - started).count()) +
            " s; analysing");
  post(RunnerEvent{RunnerEvent::Kind::kAcquired, job.record, {}, {}, {}});
  auto outcome = analyze_(job.request.part_id, *scan);
  if (!outcome) {
    const bool model = outcome.message().rfind(kPartModelErrorPrefix, 0) == 0;
    JobEnd end{regs::ResultCode::kAnalysisFailed, false, false,
               model ? regs::ErrorCode::kPartModelFailed : regs::ErrorCode::kAnalysisFailed,
               regs::ErrorDetail::kOther};
    log_.error(name + ": ANALYSIS FAILED: " + outcome.message() +
               (model ? ". The station is in FAULT (ERROR_CODE 4). Check the part's cad_file in "
                        "the config, then set ERROR_RESET (coil 3)."
                      : ". The station is in FAULT (ERROR_CODE 3). Check that the right part "
                        "(PART_ID) is on the fixture and clean, then set ERROR_RESET (coil 3)."));
    report.mutable_verdict()->add_reasons("analysis failed: " + outcome.message());
    report.mutable_input()->set_scan_points(static_cast<std::int64_t>(scan->size()));
    post(finish(job, std::move(report), nullptr, end));
    return;
  }
  const bool pass = outcome->report.verdict().pass();
  JobEnd end{pass ? regs::ResultCode::kOk : regs::ResultCode::kFormNok, pass, false,
             regs::ErrorCode::kNone, regs::ErrorDetail::kNone};
  std::string verdict = pass ? "PASS" : "FAIL";
  for (const auto& reason : outcome->report.verdict().reasons()) verdict += "; " + reason;
  log_.info(name + ": " + verdict);
  post(finish(job, std::move(outcome->report), &outcome->deviation_cloud, end));
}

RunnerEvent JobRunner::finish(const RunnerJob& job, v1::InspectionReport report,
                              const analysis::PointCloud* cloud, JobEnd end) {
  const std::string name = job_name(job);
  report.set_schema("springscan.report.v1");
  if (report.created_utc().empty()) report.set_created_utc(utc_now());
  report.set_station(settings_.station_name);
  report.set_job_id(job.request.job_id);
  report.set_result_seq(regs::result_seq_from_record(job.record));
  report.set_result_code(static_cast<std::uint32_t>(end.result_code));
  report.mutable_input()->set_part_id(std::to_string(job.request.part_id));
  if (end.result_code != regs::ResultCode::kOk) report.mutable_verdict()->set_pass(false);
  report.set_cycle_time_ms(
      std::chrono::duration<double, std::milli>(Clock::now() - job.request.trigger_time).count());
  RunnerEvent event{RunnerEvent::Kind::kFinished, job.record, end, {}, {}};
  auto stored = store_.persist(job.record, report, cloud);
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
