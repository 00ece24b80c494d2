#pragma once
// The inspection state machine: IDLE -> ACQUIRING -> ANALYZING -> DONE or FAULT, with the PLC
// handshake of docs/modbus-register-map.md ("Handshake", "Edge cases"). Pure: it sees only the
// values the PLC wrote, the scanner's presence, the time and the runner's reports, and decides
// the status bits and when a job starts. No I/O, no threads; the event loop owns it.

#include <chrono>
#include <cstdint>
#include <optional>
#include <set>
#include <vector>

#include "daemon/register_map.hpp"

namespace springscan::daemon {

using Clock = std::chrono::steady_clock;

struct MachineSettings {
  bool auto_ack_on_trigger = false;        ///< an accepted trigger also acknowledges the result
  double plc_heartbeat_timeout_s = 3.0;    ///< PLC_HEARTBEAT silent this long -> COMM_LOST; 0 off
  double trigger_release_timeout_s = 5.0;  ///< TRIGGER held past this -> TRIG_ACK off + error
  double result_ttl_s = 30.0;  ///< unacknowledged this long -> RESULT_STALE (kept valid); 0 off
  std::set<std::uint16_t> known_parts;  ///< part ids in the catalogue; empty accepts any
};

/// What the PLC wrote: coils OR-ed with CONTROL_WORD bits, and the holding registers.
struct PlcControl {
  bool trigger_enable = false;
  bool trigger = false;
  bool result_ack = false;
  bool error_reset = false;
  std::uint16_t job_id = 0;
  std::uint16_t part_id = 0;
  std::uint16_t plc_heartbeat = 0;
  std::uint32_t part_serial = 0;  ///< PART_SERIAL; 0: none
};

/// The station-side bits and codes the register image shows.
struct MachineStatus {
  regs::State state = regs::State::kIdle;
  bool ready = false;
  bool trigger_ack = false;
  bool busy = false;
  bool result_valid = false;
  bool part_ok = false;
  bool part_undecided = false;  ///< the result is RESULT_CODE UNDECIDED (never with part_ok)
  bool trigger_rejected = false;
  bool scanner_online = false;
  bool plc_comm_lost = false;
  bool result_stale = false;  ///< RESULT_VALID older than result_ttl_s, still not acknowledged
  regs::ErrorCode error_code = regs::ErrorCode::kNone;
  regs::ErrorDetail error_detail = regs::ErrorDetail::kNone;
  regs::RejectCode reject_code = regs::RejectCode::kNone;
  std::uint16_t trigger_count = 0;
  std::uint16_t reject_count = 0;
  bool error() const { return error_code != regs::ErrorCode::kNone; }
};

/// A job the runner must start: the ids latched at the trigger edge.
struct JobRequest {
  std::uint16_t job_id = 0;
  std::uint16_t part_id = 0;
  Clock::time_point trigger_time;
  std::uint32_t part_serial = 0;  ///< 0: the PLC gave none
};

/// How a job ended, as the runner reports it.
struct JobEnd {
  regs::ResultCode result_code = regs::ResultCode::kOk;
  bool part_ok = false;
  bool persisted = false;  ///< the report is on disk; only then may RESULT_VALID rise
  regs::ErrorCode error_code = regs::ErrorCode::kNone;  ///< non-zero: FAULT
  regs::ErrorDetail error_detail = regs::ErrorDetail::kNone;
};

/// Things that happened in one update, for the log.
enum class MachineEvent {
  kTriggerAccepted,
  kTriggerRejected,
  kTriggerHeldAtStart,
  kTriggerNotReleased,
  kResultAcked,
  kResultStale,  ///< result_ttl_s passed without RESULT_ACK: RESULT_STALE, result kept
  kResultClearedByJobChange,
  kErrorReset,
  kCommLost,
  kCommRestored,
};

struct MachineStep {
  std::optional<JobRequest> start;  ///< set when a trigger was accepted: run this job
  std::vector<MachineEvent> events;
};

/// The handshake and job states. Not thread-safe: one owner (the event loop) calls everything.
class InspectionMachine {
 public:
  InspectionMachine(MachineSettings settings, Clock::time_point now);

  /// Feeds the PLC's current values; call every loop iteration and after every Modbus write.
  MachineStep update(const PlcControl& plc, bool scanner_online, Clock::time_point now);
  /// The runner finished the scan and started the analysis.
  void on_acquired();
  /// The runner finished the job (persisted or not). Call update() afterwards for READY.
  void on_job_finished(const JobEnd& end, Clock::time_point now);

  const MachineStatus& status() const { return status_; }
  /// The ids latched at the last accepted trigger.
  const JobRequest& current_job() const { return job_; }

 private:
  void track_heartbeat(const PlcControl& plc, Clock::time_point now, MachineStep& step);
  void handle_reset_ack_and_ttl(const PlcControl& plc, Clock::time_point now, MachineStep& step);
  void handle_trigger(const PlcControl& plc, Clock::time_point now, MachineStep& step);
  regs::RejectCode reject_reason(const PlcControl& plc) const;
  void clear_result();
  void settle_state();

  MachineSettings settings_;
  MachineStatus status_;
  JobRequest job_;
  // Edge detection. previous_trigger_ starts high so that a TRIGGER already set at start is
  // ignored until it has been seen low (register map "Edge cases").
  bool previous_trigger_ = true;
  bool previous_ack_ = true;
  bool previous_reset_ = true;
  bool first_update_ = true;
  std::uint16_t last_heartbeat_ = 0;
  std::uint16_t previous_job_id_ = 0;
  bool fault_ = false;            ///< a job ended with an error: STATE FAULT until ERROR_RESET
  bool heartbeat_armed_ = false;  ///< the PLC has changed PLC_HEARTBEAT at least once
  Clock::time_point heartbeat_changed_;
  Clock::time_point result_time_;
};

}  // namespace springscan::daemon
