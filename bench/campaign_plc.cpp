// The fault campaign's PLC program: the handshake of docs/modbus-register-map.md with the
// recovery its "Reconnecting" and "Error codes" sections prescribe. What it collects is checked
// in campaign_checks.cpp.
#include <algorithm>
#include <thread>

#include "bench/fault_campaign_internal.hpp"

namespace springscan::bench {

namespace {

constexpr std::uint16_t kEnable = 1u << regs::kCoilTriggerEnable;
constexpr std::uint16_t kTrigger = 1u << regs::kCoilTrigger;
constexpr double kReconnectWithin_s = 15.0;  // a restart (READY) included

bool is_comm_lost(const simulators::StationStatus& s) {
  return s.live[regs::kIrErrorCode] == static_cast<std::uint16_t>(regs::ErrorCode::kPlcCommLost);
}

}  // namespace

bool Campaign::reconnect() {
  plc_.reset();
  const auto deadline = Clock::now() + std::chrono::duration<double>(kReconnectWithin_s);
  while (Clock::now() < deadline) {
    station_.check();  // a daemon that died by itself is a crash: counted and restarted
    simulators::PlcClientSettings s;
    s.port = station_.port();
    s.step_timeout_s = settings_.unrecovered_after_s / 2;
    s.poll_interval_s = 0.01;  // a PLC scan time, not a busy loop on the shared cores
    auto client = simulators::PlcClient::connect(s);
    if (client) {
      modbus_set_response_timeout((*client)->context(), 5, 0);  // a loaded 2-core machine
      plc_ = std::move(*client);
      return true;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  return false;
}

void Campaign::drop_connection() { plc_.reset(); }

void Campaign::pause_disconnected() {
  // Well below plc_heartbeat_timeout_s: a disconnect alone must not look like heartbeat loss.
  std::this_thread::sleep_for(std::chrono::duration<double>(uniform(0.02, 0.4)));
}

void Campaign::idle(double seconds) {
  const auto until = Clock::now() + std::chrono::duration<double>(seconds);
  if (plc_) {  // polling, so the PLC keeps its heartbeat going meanwhile
    auto done = plc_->wait_for([&](const auto&) { return Clock::now() >= until; }, "idle");
    if (done) return;
    drop_connection();
  }
  std::this_thread::sleep_until(until);
}

bool Campaign::make_ready() {
  const auto deadline = Clock::now() + std::chrono::duration<double>(settings_.unrecovered_after_s);
  while (Clock::now() < deadline) {
    if (!plc_ && !reconnect()) continue;
    // TRIGGER_ENABLE again each time: coils and holding registers are 0 after a restart.
    auto status = plc_->write_control(kEnable)
                      ? plc_->wait_for(
                            [](const simulators::StationStatus& s) {
                              return s.bit(regs::kDiReady) || s.bit(regs::kDiResultValid) ||
                                     s.bit(regs::kDiError);
                            },
                            "READY")
                      : analysis::Expected<simulators::StationStatus>(analysis::fail("write"));
    if (!status) {
      drop_connection();
      continue;
    }
    boot_id_ = status->live[regs::kIrBootId];
    if (status->bit(regs::kDiResultValid)) {
      bool no_drop = false;
      if (!take_result(0, no_drop)) drop_connection();  // 0: no job is expected now
      continue;
    }
    if (status->bit(regs::kDiError)) {
      if (!plc_->reset_errors()) drop_connection();
      continue;
    }
    before_ = *status;
    return true;
  }
  fail(tally_.unrecovered, "the station did not return to READY within " +
                               std::to_string(settings_.unrecovered_after_s) + " s");
  return false;
}

bool Campaign::trigger(std::uint16_t job, FaultKind kind) {
  const std::uint16_t count_before = before_.live[regs::kIrTriggerCount];
  bool written = false;
  if (kind == FaultKind::kDropAfterTrigger) {
    // Step 2 of the handshake, then the connection is gone before TRIG_ACK could be seen.
    const std::uint16_t words[3] = {static_cast<std::uint16_t>(kEnable | kTrigger), job, 1};
    written = modbus_write_registers(plc_->context(), regs::kHrControlWord, 3, words) == 3;
    drop_connection();
    pause_disconnected();
  } else {
    auto cycle = plc_->trigger(job, 1);
    if (cycle && cycle->accepted) return true;
    if (cycle) {
      ++tally_.refused;
      outcome("refused, REJECT_CODE " + std::to_string(static_cast<int>(cycle->reject_code)));
      return false;
    }
    written = true;  // the link broke somewhere in the handshake: ask the station below
    drop_connection();
  }
  // Reconnected: drop TRIGGER and tell from TRIGGER_COUNT whether the edge was accepted.
  for (int attempt = 0; attempt < 3; ++attempt) {
    if (!reconnect() || !plc_->write_control(kEnable)) continue;
    auto status = plc_->read_status();
    if (!status) continue;
    if (status->live[regs::kIrBootId] != boot_id_) return true;  // collect() sorts it out
    if (status->live[regs::kIrTriggerCount] != count_before) return true;
    if (!written) break;
    ++tally_.refused;
    outcome("refused, REJECT_CODE " + std::to_string(status->live[regs::kIrRejectCode]));
    return false;
  }
  ++tally_.refused;
  outcome("trigger not written");
  return false;
}

bool Campaign::collect(std::uint16_t job, bool drop_before_ack) {
  const auto deadline = Clock::now() + std::chrono::duration<double>(settings_.unrecovered_after_s);
  while (Clock::now() < deadline) {
    if (!plc_ && !reconnect()) continue;
    const std::uint16_t boot = boot_id_;
    auto status = plc_->wait_for(
        [boot](const simulators::StationStatus& s) {
          return s.bit(regs::kDiResultValid) || s.live[regs::kIrBootId] != boot ||
                 s.bit(regs::kDiError);
        },
        "RESULT_VALID");
    if (!status) {
      drop_connection();
      continue;
    }
    if (status->live[regs::kIrBootId] != boot) {
      after_restart(job, *status);
      return true;
    }
    if (status->bit(regs::kDiResultValid)) {
      if (take_result(job, drop_before_ack)) return true;
      continue;
    }
    // ERROR without a result: PLC_COMM_LOST (or code 6) while busy is reset at once; an error
    // that ends the job without a result is what the PLC sees instead of one.
    if (!is_comm_lost(*status) && !status->bit(regs::kDiBusy)) {
      ++tally_.error_only;
      outcome("ERROR_CODE " + std::to_string(status->live[regs::kIrErrorCode]) + ", no result");
      return true;
    }
    if (!plc_->reset_errors()) drop_connection();
  }
  fail(tally_.lost, "job " + std::to_string(job) + ": no result and no error within " +
                        std::to_string(settings_.unrecovered_after_s) + " s");
  return false;
}

bool Campaign::read_block(ResultRegisters& out) {
  // Handshake step 5: RESULT_SEQ must agree before and after the reads.
  for (int attempt = 0; attempt < 3; ++attempt) {
    out.block.assign(kBlockWords, 0);
    // In requests of at most kRecommendedChunk registers: the block is longer than one FC04
    // request may be.
    for (int done = 0; done < kBlockWords;) {
      const int count = std::min<int>(regs::kRecommendedChunk, kBlockWords - done);
      if (modbus_read_input_registers(plc_->context(), regs::kIrResultSeq + done, count,
                                      out.block.data() + done) != count)
        return false;
      done += count;
    }
    auto read = plc_->read_result();
    if (!read) return false;
    out.read = std::move(*read);
    if (out.read.seq == out.block[0]) return true;
  }
  return false;
}

bool Campaign::take_result(std::uint16_t job, bool& drop_before_ack) {
  auto status = plc_->read_status();
  ResultRegisters r;
  if (!status || !read_block(r)) return false;
  if (!status->bit(regs::kDiResultValid)) return false;  // changed meanwhile: look again
  const std::uint16_t seq = r.read.seq;
  if (acked_seqs_.count(seq) != 0) {
    fail(tally_.duplicated, "RESULT_SEQ " + std::to_string(seq) + " (job " +
                                std::to_string(r.read.job_id) + ") valid again after RESULT_ACK");
  } else if (unacked_seq_ != seq) {
    ++tally_.collected;
    check_result(job, r, "RESULT_VALID");
    outcome(result_text(*status, r.read.code));
    expect_reported(*status, r.read.code);
  } else {
    check_result(r.read.job_id, r, "RESULT_VALID (read again)");
  }
  unacked_seq_ = seq;
  if (drop_before_ack) {
    drop_before_ack = false;
    drop_connection();
    pause_disconnected();
    return false;  // the reconnected PLC finds it still valid and reads it again
  }
  return finish_result(*status, seq);
}

bool Campaign::finish_result(const simulators::StationStatus& status, std::uint16_t seq) {
  // RESULT_ACK and ERROR_RESET act on different bits: either order must keep the result.
  const bool reset_first = status.bit(regs::kDiError) && uniform(0.0, 1.0) < 0.5;
  if (reset_first && !plc_->reset_errors()) return false;
  if (!plc_->acknowledge()) return false;
  acked_seqs_.insert(seq);
  unacked_seq_.reset();
  if (status.bit(regs::kDiError) && !reset_first && !plc_->reset_errors()) return false;
  return true;
}

void Campaign::after_restart(std::uint16_t job, const simulators::StationStatus& status) {
  boot_id_ = status.live[regs::kIrBootId];
  ResultRegisters r;
  const bool read = read_block(r);
  if (read && r.read.job_id == job && r.read.seq != 0 && collected_jobs_.count(job) == 0) {
    // Stored before the kill: shown with RESULT_VALID = 0, the PLC takes it by its new seq.
    ++tally_.collected_after_restart;
    check_result(job, r, "the restored block");
    acked_seqs_.insert(r.read.seq);
    outcome("restarted; result in the restored block");
    return;
  }
  if (read && r.read.job_id == job) {
    outcome("restarted; result collected before");
    return;
  }
  const auto newest = load_record(paths_.reports, newest_record(paths_.reports));
  if (newest && newest->job_id() == job) {
    fail(tally_.lost, "job " + std::to_string(job) + " stored as seq " +
                          std::to_string(newest->result_seq()) +
                          " but the restarted station shows seq " + std::to_string(r.read.seq));
    return;
  }
  ++tally_.interrupted;
  outcome("restarted; interrupted (no report, BOOT_ID changed)");
}

}  // namespace springscan::bench
