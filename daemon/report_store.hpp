#pragma once
// The report store: one directory per inspection result, <report_dir>/r<record>/ holding the
// files report::write_inspection_files writes (report.pb, report.json, deviation.ply,
// report.html). A record is written into a hidden temporary directory, every file fsynced, then
// renamed into place and the parent fsynced, so after a crash a record is either complete or
// absent; leftovers are removed at open. Records are
// numbered 1, 2, ... over the station's life; RESULT_SEQ is derived from the number
// (regs::result_seq_from_record), so sequence numbers continue across restarts.
//
// Thread safety: persist() runs on the job runner's thread while the event loop may call
// last_record(); the record counter is guarded. open() and load_latest() run at start.

#include <cstdint>
#include <mutex>
#include <optional>
#include <string>

#include "analysis/core/expected.hpp"
#include "analysis/inspection/pipeline.hpp"
#include "proto/springscan.pb.h"

namespace springscan::daemon {

struct ReportStoreSettings {
  std::string directory = "/var/lib/springscan/reports";  ///< created if missing
  int retention = 1000;  ///< newest records kept; older ones are deleted after each persist
};

/// An outcome with a report and nothing else (a failed scan or analysis): its record has an
/// empty deviation.ply and no compensation files.
analysis::InspectionOutcome report_only(v1::InspectionReport report);

class ReportStore {
 public:
  /// Creates the directory if needed, removes interrupted writes, finds the newest record.
  static analysis::Expected<ReportStore> open(const ReportStoreSettings& settings);

  ReportStore(ReportStore&& other) noexcept;
  ReportStore& operator=(ReportStore&&) = delete;

  /// The newest complete record number (0: none).
  std::uint64_t last_record() const;
  /// The report of the newest complete record, or nullopt when there is none. An unreadable
  /// newest record is an error (the caller then shows "no result").
  analysis::Expected<std::optional<v1::InspectionReport>> load_latest() const;
  /// Writes record `record` (must be above last_record()) with report::write_inspection_files,
  /// the same files `springscan analyze` writes: report.json/.pb, deviation.ply (no vertices for
  /// a failed scan), report.html (left out when it cannot be drawn), and the compensation files
  /// when the outcome has them. Returns the record's directory.
  analysis::Expected<std::string> persist(std::uint64_t record,
                                          const analysis::InspectionOutcome& outcome);
  /// The directory of record `record`.
  std::string record_path(std::uint64_t record) const;

 private:
  explicit ReportStore(ReportStoreSettings settings);
  void apply_retention();

  ReportStoreSettings settings_;
  mutable std::mutex mutex_;
  std::uint64_t last_record_ = 0;
};

}  // namespace springscan::daemon
