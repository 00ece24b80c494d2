#pragma once
// A simulated PLC: a libmodbus client that runs the handshake of docs/modbus-register-map.md
// against springscand. Used by the springscan-plc-sim executable and by the daemon's tests.
// Not thread-safe: one owner; the connection is owned (RAII) and closed by the destructor.

#include <modbus/modbus.h>

#include <array>
#include <chrono>
#include <cstdint>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "analysis/core/expected.hpp"
#include "daemon/register_map.hpp"

namespace springscan::simulators {

namespace regs = daemon::regs;

struct PlcClientSettings {
  std::string host = "127.0.0.1";
  int port = 502;
  int unit_id = 1;
  regs::WordOrder word_order = regs::WordOrder::kAbcd;  ///< must match the daemon's config
  double step_timeout_s = 60.0;    ///< longest wait for one handshake step (TRIG_ACK, RESULT)
  double poll_interval_s = 0.002;  ///< between two status reads
  bool send_heartbeat = true;      ///< change PLC_HEARTBEAT while waiting
};

/// The station's status bits and live registers, as one read shows them.
struct StationStatus {
  std::array<bool, regs::kDiCount> bits{};
  std::array<std::uint16_t, regs::kLiveCount> live{};
  bool bit(std::uint16_t address) const { return bits[address]; }
};

/// The frozen result block as the PLC reads it (scaled integers, as on the wire).
struct ResultRead {
  std::uint16_t seq = 0;
  std::uint16_t part_id = 0;
  std::uint16_t job_id = 0;
  regs::ResultCode code = regs::ResultCode::kNoData;
  std::int32_t max_deviation_um = 0;
  std::int32_t rms_deviation_um = 0;
  std::int32_t cycle_time_ms = 0;
  std::vector<std::int32_t> springback_mdeg;  ///< per bend record
  std::vector<std::uint16_t> bend_flags;
  std::vector<std::array<std::int32_t, 3>> vectors_um;
  int reads = 0;  ///< FC04 requests it took
};

/// One handshake cycle as the PLC saw it.
struct CycleResult {
  bool accepted = false;  ///< TRIG_ACK came (else TRIGGER_REJECTED)
  regs::RejectCode reject_code = regs::RejectCode::kNone;
  bool part_ok = false;
  bool part_undecided = false;   ///< PART_UNDECIDED (register map version 6)
  std::uint16_t error_code = 0;  ///< ERROR_CODE when RESULT_VALID rose
  ResultRead result;
  double trigger_to_ack_ms = 0.0;
  double trigger_to_valid_ms = 0.0;  ///< trigger write -> RESULT_VALID seen
};

/// Where a PLC program sends a part (docs/modbus-register-map.md "An undecided part").
enum class PartRoute {
  kGood,         ///< RESULT_CODE 0 (PART_OK)
  kReject,       ///< RESULT_CODE 1 or 5: out of tolerance, or the analysis cannot be trusted
  kManualCheck,  ///< UNDECIDED twice, or no result on the re-measure: a person decides
  kNoResult,     ///< the first scan or analysis failed (RESULT_CODE 2, 3, 4): the station's fault
};

const char* to_string(PartRoute route);  ///< "good", "reject", "manual check", "no result"

/// One part through the station: its cycles (two when the first was UNDECIDED) and its route.
struct PartInspection {
  std::vector<CycleResult> cycles;
  PartRoute route = PartRoute::kNoResult;
};

class PlcClient {
 public:
  static analysis::Expected<std::unique_ptr<PlcClient>> connect(const PlcClientSettings& settings);
  ~PlcClient();
  PlcClient(const PlcClient&) = delete;
  PlcClient& operator=(const PlcClient&) = delete;

  /// The whole handshake: ids + TRIGGER in one FC16 write, wait TRIG_ACK (or the rejection),
  /// drop TRIGGER, wait RESULT_VALID, read the result consistently, RESULT_ACK (if `ack`).
  analysis::Expected<CycleResult> run_cycle(std::uint16_t job_id, std::uint16_t part_id,
                                            bool ack = true);
  /// A part as a PLC program of map version 6 runs it: one cycle; on RESULT_CODE 6 UNDECIDED
  /// one re-measure (same JOB_ID and PART_ID), whose PASS or FAIL decides; UNDECIDED again, or
  /// no result, routes the part to a manual check. A refused trigger ends it (route kNoResult).
  analysis::Expected<PartInspection> inspect_part(std::uint16_t job_id, std::uint16_t part_id);
  /// Only the first half: trigger and wait for TRIG_ACK or TRIGGER_REJECTED; drops TRIGGER.
  analysis::Expected<CycleResult> trigger(std::uint16_t job_id, std::uint16_t part_id);
  /// PART_SERIAL written before each later trigger (0: none), as a PLC tracking parts does.
  void set_part_serial(std::uint32_t serial) { part_serial_ = serial; }
  /// Waits for RESULT_VALID, reads the block (checking RESULT_SEQ before and after).
  analysis::Expected<CycleResult> wait_result(CycleResult cycle,
                                              std::chrono::steady_clock::time_point triggered);
  /// RESULT_ACK edge, waits for RESULT_VALID = 0, drops the ACK.
  analysis::Expected<bool> acknowledge();
  /// ERROR_RESET edge, then drops it.
  analysis::Expected<bool> reset_errors();
  /// Waits until `predicate(status)` holds (or the step timeout).
  template <typename Predicate>
  analysis::Expected<StationStatus> wait_for(Predicate predicate, const char* what);

  analysis::Expected<StationStatus> read_status();
  analysis::Expected<ResultRead> read_result();
  /// Writes CONTROL_WORD (bit i = coil i); the coils themselves are left at 0.
  analysis::Expected<bool> write_control(std::uint16_t word);
  /// Pauses (a PLC program stopped: heartbeat loss) or resumes PLC_HEARTBEAT while waiting.
  /// Resuming writes a new value at once, so an ERROR_RESET right after it finds the
  /// heartbeat running (register map "Reconnecting").
  analysis::Expected<bool> set_heartbeat(bool on);
  modbus_t* context() { return ctx_; }

 private:
  explicit PlcClient(PlcClientSettings settings) : settings_(std::move(settings)) {}
  analysis::Expected<bool> beat();

  PlcClientSettings settings_;
  modbus_t* ctx_ = nullptr;
  std::uint16_t heartbeat_ = 0;
  std::uint32_t part_serial_ = 0;
  std::chrono::steady_clock::time_point last_beat_;
};

template <typename Predicate>
analysis::Expected<StationStatus> PlcClient::wait_for(Predicate predicate, const char* what) {
  const auto deadline = std::chrono::steady_clock::now() +
                        std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                            std::chrono::duration<double>(settings_.step_timeout_s));
  for (;;) {
    auto status = read_status();
    if (!status) return status;
    if (predicate(*status)) return status;
    if (std::chrono::steady_clock::now() > deadline) {
      return analysis::fail(std::string("timed out waiting for ") + what);
    }
    auto beaten = beat();
    if (!beaten) return analysis::fail(beaten.message());
    std::this_thread::sleep_for(std::chrono::duration<double>(settings_.poll_interval_s));
  }
}

}  // namespace springscan::simulators
