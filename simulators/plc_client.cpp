#include "simulators/plc_client.hpp"

#include <cerrno>
#include <optional>

namespace springscan::simulators {

using analysis::Expected;
using analysis::fail;
using Clock = std::chrono::steady_clock;

namespace {

constexpr std::uint16_t kEnable = 1u << regs::kCoilTriggerEnable;
constexpr std::uint16_t kTrigger = 1u << regs::kCoilTrigger;
constexpr std::uint16_t kAck = 1u << regs::kCoilResultAck;
constexpr std::uint16_t kReset = 1u << regs::kCoilErrorReset;

std::string modbus_error(const char* what) {
  return std::string(what) + ": " + modbus_strerror(errno);
}

double ms_since(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

}  // namespace

Expected<std::unique_ptr<PlcClient>> PlcClient::connect(const PlcClientSettings& settings) {
  std::unique_ptr<PlcClient> client(new PlcClient(settings));
  client->ctx_ = modbus_new_tcp(settings.host.c_str(), settings.port);
  if (client->ctx_ == nullptr) return fail(modbus_error("modbus_new_tcp"));
  modbus_set_slave(client->ctx_, settings.unit_id);
  modbus_set_response_timeout(client->ctx_, 2, 0);
  if (modbus_connect(client->ctx_) != 0) {
    return fail(modbus_error(
        ("connect to " + settings.host + ":" + std::to_string(settings.port)).c_str()));
  }
  client->last_beat_ = Clock::now();
  return client;
}

PlcClient::~PlcClient() {
  if (ctx_ != nullptr) {
    modbus_close(ctx_);
    modbus_free(ctx_);
  }
}

Expected<bool> PlcClient::beat() {
  if (!settings_.send_heartbeat || Clock::now() - last_beat_ < std::chrono::milliseconds(100)) {
    return true;
  }
  last_beat_ = Clock::now();
  if (modbus_write_register(ctx_, regs::kHrPlcHeartbeat, ++heartbeat_) != 1) {
    return fail(modbus_error("write PLC_HEARTBEAT"));
  }
  return true;
}

Expected<bool> PlcClient::set_heartbeat(bool on) {
  settings_.send_heartbeat = on;
  if (!on) return true;
  last_beat_ = Clock::now() - std::chrono::seconds(1);  // due now
  return beat();
}

Expected<StationStatus> PlcClient::read_status() {
  StationStatus status;
  std::uint8_t bits[regs::kDiCount];
  if (modbus_read_input_bits(ctx_, 0, regs::kDiCount, bits) != regs::kDiCount) {
    return fail(modbus_error("read discrete inputs"));
  }
  for (int i = 0; i < regs::kDiCount; ++i) status.bits[i] = bits[i] != 0;
  if (modbus_read_input_registers(ctx_, 0, regs::kLiveCount, status.live.data()) !=
      regs::kLiveCount) {
    return fail(modbus_error("read live registers"));
  }
  return status;
}

Expected<bool> PlcClient::write_control(std::uint16_t word) {
  if (modbus_write_register(ctx_, regs::kHrControlWord, word) != 1) {
    return fail(modbus_error("write CONTROL_WORD"));
  }
  return true;
}

Expected<ResultRead> PlcClient::read_result() {
  ResultRead r;
  // The result block up to the end of the bend records: 116 registers, one FC04 request (the
  // bend shape table after it would make the request longer than Modbus allows).
  std::uint16_t block[regs::kIrBendShapeTable - regs::kIrResultSeq];
  constexpr int kBlockWords = regs::kIrBendShapeTable - regs::kIrResultSeq;
  if (modbus_read_input_registers(ctx_, regs::kIrResultSeq, kBlockWords, block) != kBlockWords) {
    return fail(modbus_error("read result block"));
  }
  ++r.reads;
  const auto at = [&block](std::uint16_t address) {
    return block + (address - regs::kIrResultSeq);
  };
  const auto i32 = [&](std::uint16_t address) {
    return regs::decode_int32(at(address), settings_.word_order);
  };
  r.seq = *at(regs::kIrResultSeq);
  r.part_id = *at(regs::kIrResultPartId);
  r.job_id = *at(regs::kIrResultJobId);
  r.code = static_cast<regs::ResultCode>(*at(regs::kIrResultCode));
  r.max_deviation_um = i32(regs::kIrMaxDeviation);
  r.rms_deviation_um = i32(regs::kIrRmsDeviation);
  r.cycle_time_ms = i32(regs::kIrCycleTimeMs);
  const int bends = std::min<int>(*at(regs::kIrBendCount), regs::kMaxBends);
  for (int j = 0; j < bends; ++j) {
    const auto base = static_cast<std::uint16_t>(regs::kIrBendTable + j * regs::kBendRecordSize);
    r.bend_flags.push_back(*at(base + regs::kBendFlags));
    r.springback_mdeg.push_back(i32(static_cast<std::uint16_t>(base + regs::kBendSpringback)));
  }
  // The vector block in chunks of at most 120 registers (15 whole records).
  const int vectors = std::min<int>(*at(regs::kIrVectorCount), regs::kMaxVectors);
  std::vector<std::uint16_t> words(static_cast<std::size_t>(vectors) * regs::kVectorRecordSize);
  for (std::size_t done = 0; done < words.size();) {
    const int count =
        static_cast<int>(std::min<std::size_t>(regs::kRecommendedChunk, words.size() - done));
    const auto address = static_cast<int>(regs::kIrVectors + done);
    if (modbus_read_input_registers(ctx_, address, count, words.data() + done) != count) {
      return fail(modbus_error("read vector block"));
    }
    ++r.reads;
    done += static_cast<std::size_t>(count);
  }
  for (int i = 0; i < vectors; ++i) {
    const std::uint16_t* rec = words.data() + i * regs::kVectorRecordSize;
    r.vectors_um.push_back({regs::decode_int32(rec + regs::kVectorDx, settings_.word_order),
                            regs::decode_int32(rec + regs::kVectorDy, settings_.word_order),
                            regs::decode_int32(rec + regs::kVectorDz, settings_.word_order)});
  }
  return r;
}

Expected<CycleResult> PlcClient::trigger(std::uint16_t job_id, std::uint16_t part_id) {
  CycleResult cycle;
  // PART_SERIAL first: the station latches it with the ids at the trigger edge.
  if (part_serial_ != 0) {
    std::uint16_t serial[2];
    regs::encode_int32(static_cast<std::int32_t>(part_serial_), settings_.word_order, serial);
    if (modbus_write_registers(ctx_, regs::kHrPartSerial, 2, serial) != 2)
      return fail(modbus_error("write PART_SERIAL"));
  }
  // Handshake step 2: CONTROL_WORD, JOB_ID and PART_ID in one FC16 write.
  const std::uint16_t words[3] = {static_cast<std::uint16_t>(kEnable | kTrigger), job_id, part_id};
  const auto start = Clock::now();
  if (modbus_write_registers(ctx_, regs::kHrControlWord, 3, words) != 3) {
    return fail(modbus_error("write trigger"));
  }
  auto seen = wait_for(
      [](const StationStatus& s) {
        return s.bit(regs::kDiTriggerAck) || s.bit(regs::kDiTriggerRejected);
      },
      "TRIG_ACK or TRIGGER_REJECTED");
  if (!seen) return fail(seen.message());
  cycle.trigger_to_ack_ms = ms_since(start);
  cycle.accepted = seen->bit(regs::kDiTriggerAck);
  cycle.reject_code = static_cast<regs::RejectCode>(seen->live[regs::kIrRejectCode]);
  auto dropped = write_control(kEnable);  // step 3: the PLC drops TRIGGER
  if (!dropped) return fail(dropped.message());
  return cycle;
}

Expected<CycleResult> PlcClient::wait_result(CycleResult cycle, Clock::time_point triggered) {
  auto valid =
      wait_for([](const StationStatus& s) { return s.bit(regs::kDiResultValid); }, "RESULT_VALID");
  if (!valid) return fail(valid.message());
  cycle.trigger_to_valid_ms = ms_since(triggered);
  cycle.part_ok = valid->bit(regs::kDiPartOk);
  cycle.part_undecided = valid->bit(regs::kDiPartUndecided);
  cycle.error_code = valid->live[regs::kIrErrorCode];
  // Step 5: RESULT_SEQ before and after the multi-read must agree.
  for (int attempt = 0; attempt < 3; ++attempt) {
    auto first = read_result();
    if (!first) return fail(first.message());
    std::uint16_t seq_after = 0;
    if (modbus_read_input_registers(ctx_, regs::kIrResultSeq, 1, &seq_after) != 1) {
      return fail(modbus_error("re-read RESULT_SEQ"));
    }
    if (seq_after == first->seq) {
      cycle.result = std::move(*first);
      return cycle;
    }
  }
  return fail("RESULT_SEQ kept changing during the read");
}

Expected<CycleResult> PlcClient::run_cycle(std::uint16_t job_id, std::uint16_t part_id, bool ack) {
  const auto start = Clock::now();
  auto cycle = trigger(job_id, part_id);
  if (!cycle || !cycle->accepted) return cycle;
  auto done = wait_result(std::move(*cycle), start);
  if (!done || !ack) return done;
  auto acked = acknowledge();
  if (!acked) return fail(acked.message());
  return done;
}

const char* to_string(PartRoute route) {
  switch (route) {
    case PartRoute::kGood:
      return "good";
    case PartRoute::kReject:
      return "reject";
    case PartRoute::kManualCheck:
      return "manual check";
    case PartRoute::kNoResult:
      break;
  }
  return "no result";
}

namespace {

// The route of one result; nullopt: the part is not decided yet (UNDECIDED).
std::optional<PartRoute> route_of(const CycleResult& cycle) {
  switch (cycle.result.code) {
    case regs::ResultCode::kOk:
      return cycle.part_ok ? PartRoute::kGood : PartRoute::kNoResult;
    case regs::ResultCode::kFormNok:
    case regs::ResultCode::kAmbiguous:
      return PartRoute::kReject;
    case regs::ResultCode::kUndecided:
      return std::nullopt;
    default:
      return PartRoute::kNoResult;
  }
}

}  // namespace

Expected<PartInspection> PlcClient::inspect_part(std::uint16_t job_id, std::uint16_t part_id) {
  PartInspection part;
  for (int attempt = 0; attempt < 2; ++attempt) {
    auto cycle = run_cycle(job_id, part_id);
    if (!cycle) return fail(cycle.message());
    part.cycles.push_back(*cycle);
    if (!cycle->accepted) return part;  // kNoResult: the trigger was refused
    const std::optional<PartRoute> route = route_of(*cycle);
    if (route) {
      // No result on the re-measure: the first said the station cannot tell; a person decides.
      part.route =
          attempt == 1 && *route == PartRoute::kNoResult ? PartRoute::kManualCheck : *route;
      return part;
    }
  }
  part.route = PartRoute::kManualCheck;  // UNDECIDED twice
  return part;
}

Expected<bool> PlcClient::acknowledge() {
  auto set = write_control(kEnable | kAck);
  if (!set) return set;
  auto cleared = wait_for([](const StationStatus& s) { return !s.bit(regs::kDiResultValid); },
                          "RESULT_VALID = 0 after RESULT_ACK");
  if (!cleared) return fail(cleared.message());
  return write_control(kEnable);
}

Expected<bool> PlcClient::reset_errors() {
  auto set = write_control(kEnable | kReset);
  if (!set) return set;
  auto cleared = wait_for([](const StationStatus& s) { return !s.bit(regs::kDiError); },
                          "ERROR = 0 after ERROR_RESET");
  if (!cleared) return fail(cleared.message());
  return write_control(kEnable);
}

}  // namespace springscan::simulators
