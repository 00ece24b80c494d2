#pragma once
// The job runner: one worker thread that owns every call to the scanner, runs the analysis and
// persists the report, so the event loop never waits on any of them (DESIGN.md "The daemon").
// The scanner and the analysis are injected: the daemon passes the USB driver and
// run_inspection with the part's cached model; tests pass their own.
//
// Results come back as events on a queue; wake_fd() (an eventfd) becomes readable when one is
// waiting, so the loop can poll() it with the sockets.

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <functional>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "analysis/core/expected.hpp"
#include "analysis/inspection/pipeline.hpp"
#include "daemon/log.hpp"
#include "daemon/report_store.hpp"
#include "daemon/result_block.hpp"
#include "daemon/state_machine.hpp"
#include "drivers/scanner.hpp"

namespace springscan::daemon {

/// Starts the message of an AnalyzeFn error that is about the part's CAD model, for the person
/// reading the log and the report. Text only: the runner decides ERROR_CODE 4 (part model) vs 3
/// (analysis) by the error's code (plc_error_for_analysis), never by this prefix.
inline constexpr const char* kPartModelErrorPrefix = "part model: ";

/// Analyses one scan of part `part_id`. Called on the runner's thread, one call at a time.
/// Errors carry their code through (plc_error_for_analysis maps it for the PLC): kNotFound,
/// kIoError, kCorruption or kInvalidSettings for the part's CAD model or settings, anything else
/// for the analysis of the scan.
using AnalyzeFn = std::function<analysis::Expected<analysis::InspectionOutcome>(
    std::uint16_t part_id, const analysis::PointCloud& scan)>;

struct RunnerSettings {
  std::string station_name = "springscan";  ///< written into every report
  double probe_interval_s = 1.0;  ///< how often an idle runner checks (and reopens) the scanner
  /// The check part (config check_part, docs/calibration.md): a report of its part id is
  /// compared with the references (report/check_part.hpp) into InspectionReport.check.
  std::optional<v1::CheckPartConfig> check_part;
};

struct RunnerJob {
  std::uint64_t record = 0;  ///< report store record number; RESULT_SEQ derives from it
  JobRequest request;
};

struct RunnerEvent {
  enum class Kind { kAcquired, kFinished };
  Kind kind = Kind::kFinished;
  std::uint64_t record = 0;
  JobEnd end;               ///< kFinished only
  ResultBlock block;        ///< kFinished and end.persisted only
  std::string report_path;  ///< kFinished and end.persisted only
  /// kFinished of the check part when its scan was analysed: its comparison (report.check).
  std::optional<v1::CheckResult> check;
};

class JobRunner {
 public:
  /// `scanner`, `store` and `log` are not owned and must outlive the runner.
  JobRunner(drivers::Scanner& scanner, AnalyzeFn analyze, ReportStore& store, Log& log,
            RunnerSettings settings = {});
  /// Cancels a running scan (through its progress callback), waits for the thread.
  ~JobRunner();
  JobRunner(const JobRunner&) = delete;
  JobRunner& operator=(const JobRunner&) = delete;

  /// Queues a job. Precondition: the previous job's kFinished event was taken.
  void start(const RunnerJob& job);
  /// The events since the last call, in order; clears wake_fd().
  std::vector<RunnerEvent> take_events();
  int wake_fd() const { return wake_fd_; }
  /// The scanner's presence as last seen by the worker (it alone talks to the scanner).
  bool scanner_online() const { return online_.load(); }
  std::uint16_t progress_pct() const { return progress_pct_.load(); }

 private:
  void worker();
  void run(const RunnerJob& job);
  void probe_scanner();
  void post(RunnerEvent event);
  RunnerEvent finish(const RunnerJob& job, analysis::InspectionOutcome outcome, JobEnd end);
  std::optional<v1::CheckResult> check_part(const RunnerJob& job, v1::InspectionReport& report);

  drivers::Scanner& scanner_;
  AnalyzeFn analyze_;
  ReportStore& store_;
  Log& log_;
  RunnerSettings settings_;
  int wake_fd_ = -1;
  std::mutex mutex_;
  std::condition_variable wake_worker_;
  std::optional<RunnerJob> pending_;
  std::deque<RunnerEvent> events_;
  bool stop_ = false;
  std::atomic<bool> cancel_{false};
  std::atomic<bool> online_{false};
  std::atomic<std::uint16_t> progress_pct_{0};
  std::thread thread_;
};

/// What the PLC is told about a failure: ERROR_CODE and ERROR_DETAIL (input registers 4, 5).
struct PlcError {
  regs::ErrorCode code = regs::ErrorCode::kNone;
  regs::ErrorDetail detail = regs::ErrorDetail::kNone;
  bool operator==(const PlcError&) const = default;
};

/// ERROR_CODE / ERROR_DETAIL for a failed scan, from the code of Scanner::scan's error
/// (docs/modbus-register-map.md, "Error codes"). A switch over every code: no message text.
PlcError plc_error_for_scan(analysis::ErrorCode code);
/// ERROR_CODE / ERROR_DETAIL for a failed analysis, from the code of the AnalyzeFn's error:
/// files and settings of the part (the only files an analysis reads) give 4, the rest 3.
PlcError plc_error_for_analysis(analysis::ErrorCode code);
/// ERROR_CODE / ERROR_DETAIL beside an analysed part's result: a datum that could not be
/// measured (`alignment` not achieved, its datum named) gives 3 / 10, the part's result stays
/// its verdict (never PASS); none otherwise.
std::optional<PlcError> plc_error_for_alignment(const v1::Alignment& alignment);

}  // namespace springscan::daemon
