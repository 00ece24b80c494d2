#include "daemon/state_machine.hpp"

namespace springscan::daemon {

namespace {

bool older_than(Clock::time_point since, Clock::time_point now, double seconds) {
  return seconds > 0.0 && now - since > std::chrono::duration<double>(seconds);
}

}  // namespace

InspectionMachine::InspectionMachine(MachineSettings settings, Clock::time_point now)
    : settings_(std::move(settings)), heartbeat_changed_(now), result_time_(now) {}

MachineStep InspectionMachine::update(const PlcControl& plc, bool scanner_online,
                                      Clock::time_point now) {
  MachineStep step;
  status_.scanner_online = scanner_online;
  if (first_update_) {
    // A trigger held high at start is not an edge; say so once so the log explains the silence.
    if (plc.trigger) step.events.push_back(MachineEvent::kTriggerHeldAtStart);
    last_heartbeat_ = plc.plc_heartbeat;
    previous_job_id_ = plc.job_id;
    first_update_ = false;
  }
  track_heartbeat(plc, now, step);
  handle_reset_ack_and_ttl(plc, now, step);
  handle_trigger(plc, now, step);
  settle_state();
  previous_trigger_ = plc.trigger;
  previous_ack_ = plc.result_ack;
  previous_reset_ = plc.error_reset;
  // READY (register map "Handshake" step 1).
  status_.ready = plc.trigger_enable && scanner_online && !status_.error() && !status_.busy &&
                  !status_.plc_comm_lost &&
                  (!status_.result_valid || settings_.auto_ack_on_trigger);
  return step;
}

void InspectionMachine::track_heartbeat(const PlcControl& plc, Clock::time_point now,
                                        MachineStep& step) {
  if (plc.plc_heartbeat != last_heartbeat_) {
    last_heartbeat_ = plc.plc_heartbeat;
    heartbeat_changed_ = now;
    heartbeat_armed_ = true;
  }
  // Monitoring starts with the PLC's first heartbeat, so a PLC program without one still works.
  if (heartbeat_armed_ && !status_.plc_comm_lost &&
      older_than(heartbeat_changed_, now, settings_.plc_heartbeat_timeout_s)) {
    status_.plc_comm_lost = true;
    // ERROR and ERROR_CODE say why READY dropped; an error already latched keeps its code.
    if (!status_.error()) status_.error_code = regs::ErrorCode::kPlcCommLost;
    step.events.push_back(MachineEvent::kCommLost);
  }
}

void InspectionMachine::handle_reset_ack_and_ttl(const PlcControl& plc, Clock::time_point now,
                                                 MachineStep& step) {
  if (plc.error_reset && !previous_reset_) {
    // Clears the errors only: a valid result stays valid (and unacknowledged) across a reset,
    // so a PLC may reset and acknowledge in either order (register map "Reconnecting").
    status_.error_code = regs::ErrorCode::kNone;
    status_.error_detail = regs::ErrorDetail::kNone;
    status_.trigger_rejected = false;
    status_.reject_code = regs::RejectCode::kNone;
    fault_ = false;
    if (status_.plc_comm_lost) {
      if (!older_than(heartbeat_changed_, now, settings_.plc_heartbeat_timeout_s)) {
        status_.plc_comm_lost = false;
        step.events.push_back(MachineEvent::kCommRestored);
      } else {
        status_.error_code = regs::ErrorCode::kPlcCommLost;  // still silent: stays latched
      }
    }
    step.events.push_back(MachineEvent::kErrorReset);
  }
  if (plc.result_ack && !previous_ack_ && status_.result_valid) {
    clear_result();
    step.events.push_back(MachineEvent::kResultAcked);
  }
  if (status_.result_valid && plc.job_id != previous_job_id_) {
    // JOB_ID changed while the result was shown: the PLC moved on without acknowledging, the
    // old result is stale for it. (A change while busy, e.g. by a refused trigger, is not.)
    clear_result();
    step.events.push_back(MachineEvent::kResultClearedByJobChange);
  }
  previous_job_id_ = plc.job_id;
  if (status_.result_valid && !status_.result_stale &&
      older_than(result_time_, now, settings_.result_ttl_s)) {
    // "None lost": the result stays valid until acknowledged or superseded; the flag says the
    // PLC has not collected it in time (its report is on disk either way).
    status_.result_stale = true;
    step.events.push_back(MachineEvent::kResultStale);
  }
}

void InspectionMachine::handle_trigger(const PlcControl& plc, Clock::time_point now,
                                       MachineStep& step) {
  if (plc.trigger && !previous_trigger_) {
    const regs::RejectCode reason = reject_reason(plc);
    if (reason != regs::RejectCode::kNone) {
      // No Modbus exception: PLC function blocks treat exceptions as communication faults.
      status_.trigger_rejected = true;
      status_.reject_code = reason;
      ++status_.reject_count;
      step.events.push_back(MachineEvent::kTriggerRejected);
    } else {
      job_ = JobRequest{plc.job_id, plc.part_id, now, plc.part_serial};
      clear_result();
      status_.busy = true;
      status_.trigger_ack = true;
      status_.trigger_rejected = false;
      status_.reject_code = regs::RejectCode::kNone;
      status_.state = regs::State::kAcquiring;
      ++status_.trigger_count;
      step.start = job_;
      step.events.push_back(MachineEvent::kTriggerAccepted);
    }
  }
  if (status_.trigger_ack && !plc.trigger) status_.trigger_ack = false;
  if (status_.trigger_ack &&
      older_than(job_.trigger_time, now, settings_.trigger_release_timeout_s)) {
    // The Omron pattern: force the acknowledge off and tell the PLC its program is stuck.
    status_.trigger_ack = false;
    status_.error_code = regs::ErrorCode::kTriggerNotReleased;
    status_.error_detail = regs::ErrorDetail::kNone;
    step.events.push_back(MachineEvent::kTriggerNotReleased);
  }
}

regs::RejectCode InspectionMachine::reject_reason(const PlcControl& plc) const {
  using regs::RejectCode;
  if (status_.busy) return RejectCode::kBusy;
  if (!plc.trigger_enable) return RejectCode::kNotEnabled;
  if (status_.plc_comm_lost) return RejectCode::kCommLost;
  if (status_.error()) return RejectCode::kErrorActive;
  if (!status_.scanner_online) return RejectCode::kScannerOffline;
  if (status_.result_valid && !settings_.auto_ack_on_trigger) return RejectCode::kResultNotAcked;
  if (!settings_.known_parts.empty() && settings_.known_parts.count(plc.part_id) == 0) {
    return RejectCode::kUnknownPart;
  }
  return RejectCode::kNone;
}

void InspectionMachine::clear_result() {
  status_.result_valid = false;
  status_.part_ok = false;
  status_.part_undecided = false;
  status_.result_stale = false;
}

void InspectionMachine::settle_state() {
  // Between jobs: FAULT until ERROR_RESET after a failed job, else DONE while a result is shown,
  // else IDLE. ERROR_CODE 6 or 7 alone does not make a FAULT (STATE stays DONE or IDLE).
  if (status_.busy) return;
  status_.state = fault_                 ? regs::State::kFault
                  : status_.result_valid ? regs::State::kDone
                                         : regs::State::kIdle;
}

void InspectionMachine::on_acquired() {
  if (status_.busy) status_.state = regs::State::kAnalyzing;
}

void InspectionMachine::on_job_finished(const JobEnd& end, Clock::time_point now) {
  status_.busy = false;
  if (!end.persisted) {
    // A result that is not on disk is never announced (DESIGN.md "The daemon").
    status_.result_valid = false;
    status_.part_ok = false;
    status_.part_undecided = false;
    status_.error_code = end.error_code != regs::ErrorCode::kNone
                             ? end.error_code
                             : regs::ErrorCode::kReportWriteFailed;
    status_.error_detail = end.error_detail;
    fault_ = true;
    settle_state();
    return;
  }
  status_.result_valid = true;
  status_.result_stale = false;
  status_.part_ok = end.part_ok && end.result_code == regs::ResultCode::kOk;
  // Never together with PART_OK: an UNDECIDED part is not OK (register map version 6).
  status_.part_undecided = end.result_code == regs::ResultCode::kUndecided;
  result_time_ = now;
  if (end.error_code != regs::ErrorCode::kNone) {
    status_.error_code = end.error_code;
    status_.error_detail = end.error_detail;
    fault_ = true;
  }
  settle_state();
}

}  // namespace springscan::daemon
