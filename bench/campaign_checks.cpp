// The fault campaign's checks of what the PLC collected: every result against the report stored
// on disk (stale), against the jobs already collected (duplicated), and against the fault that
// was injected (misreported); and the bookkeeping of outcomes and failures.
#include <cstdio>

#include "bench/fault_campaign_internal.hpp"

namespace springscan::bench {

std::string result_text(const simulators::StationStatus& s, regs::ResultCode code) {
  std::string text = "RESULT_CODE " + std::to_string(static_cast<int>(code));
  if (s.bit(regs::kDiError)) {
    text += ", ERROR_CODE " + std::to_string(s.live[regs::kIrErrorCode]);
    if (s.live[regs::kIrErrorDetail] != 0)
      text += " DETAIL " + std::to_string(s.live[regs::kIrErrorDetail]);
  }
  return text;
}

void Campaign::check_result(std::uint16_t job, const ResultRegisters& r, const char* how) {
  const std::uint16_t seq = r.read.seq;
  const std::string what =
      std::string(how) + " seq " + std::to_string(seq) + " job " + std::to_string(r.read.job_id);
  if (r.read.job_id != job) {
    fail(collected_jobs_.count(r.read.job_id) ? tally_.duplicated : tally_.stale,
         what + " while the PLC waits for job " + std::to_string(job));
    return;
  }
  if (collected_jobs_.count(job) != 0 && unacked_seq_ != seq) {
    fail(tally_.duplicated, what + ": the job's second result");
    return;
  }
  collected_jobs_.insert(job);
  // RESULT_SEQ == record number while fewer than 65535 results exist
  // (regs::result_seq_from_record).
  const auto stored = load_record(paths_.reports, seq);
  if (!stored) return fail(tally_.stale, what + ": no stored report for that seq");
  const std::string diff = difference(r.block, r.read, *stored, regs::WordOrder::kAbcd);
  if (!diff.empty()) fail(tally_.stale, what + ": " + diff);
}

void Campaign::expect_reported(const simulators::StationStatus& status, regs::ResultCode code) {
  using D = regs::ErrorDetail;
  D expected = D::kNone;  // an analysed part: RESULT_CODE 0, 1 or 5, no scan error
  switch (kind_) {
    case FaultKind::kUnplug:
      expected = D::kDeviceGone;
      break;
    case FaultKind::kStuckHalt:
      expected = D::kStalledEndpoint;
      break;
    case FaultKind::kBadCrc:
      expected = D::kCorruptData;
      break;
    case FaultKind::kSequenceGap:
      expected = D::kSequenceGap;
      break;
    case FaultKind::kScanTimeout:
      expected = D::kTimeout;
      break;
    default:
      break;
  }
  const bool scan_failed = code == regs::ResultCode::kScanFailed;
  const auto detail = static_cast<D>(status.live[regs::kIrErrorDetail]);
  const bool as_injected = expected == D::kNone
                               ? !scan_failed && code != regs::ResultCode::kAnalysisFailed
                               : scan_failed && detail == expected;
  if (!as_injected)
    fail(tally_.misreported, result_text(status, code) + " where ERROR_DETAIL " +
                                 std::to_string(static_cast<int>(expected)) + " was due");
}

void Campaign::outcome(const std::string& text) {
  ++tally_.kinds[static_cast<int>(kind_)].outcomes[text];
}

void Campaign::fail(int& counter, const std::string& note) {
  ++counter;
  tally_.notes.push_back(std::string("cycle ") + std::to_string(tally_.cycles_run + 1) + " (" +
                         fault_name(kind_) + "): " + note);
  std::fprintf(stderr, "FAILURE %s\n", tally_.notes.back().c_str());
}

}  // namespace springscan::bench
