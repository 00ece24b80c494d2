#include "daemon/register_image.hpp"

#include <algorithm>
#include <new>

namespace springscan::daemon {

namespace {

constexpr std::uint16_t bit(bool value, int position) {
  return value ? static_cast<std::uint16_t>(1u << position) : std::uint16_t{0};
}

}  // namespace

RegisterImage::RegisterImage(regs::WordOrder order)
    : mapping_(modbus_mapping_new_start_address(0, regs::kCoilCount, 0, regs::kDiCount, 0,
                                                regs::kInputRegisterCount, 0,
                                                regs::kInputRegisterCount)),
      order_(order) {
  if (!mapping_) throw std::bad_alloc();
  ResultBlock empty;
  publish_result(empty);
  publish_status(MachineStatus{}, LiveValues{});
}

PlcControl RegisterImage::plc_control() const {
  const auto* m = mapping_.get();
  const std::uint16_t word = m->tab_registers[regs::kHrControlWord];
  const auto control = [&](std::uint16_t coil) {
    return m->tab_bits[coil] != 0 || (word & (1u << coil)) != 0;
  };
  PlcControl plc;
  plc.trigger_enable = control(regs::kCoilTriggerEnable);
  plc.trigger = control(regs::kCoilTrigger);
  plc.result_ack = control(regs::kCoilResultAck);
  plc.error_reset = control(regs::kCoilErrorReset);
  plc.job_id = m->tab_registers[regs::kHrJobId];
  plc.part_id = m->tab_registers[regs::kHrPartId];
  plc.plc_heartbeat = m->tab_registers[regs::kHrPlcHeartbeat];
  plc.part_serial = static_cast<std::uint32_t>(
      regs::decode_int32(&m->tab_registers[regs::kHrPartSerial], order_));
  return plc;
}

void RegisterImage::publish_status(const MachineStatus& s, const LiveValues& live) {
  auto* m = mapping_.get();
  const bool heartbeat_bit = ((live.heartbeat / 10) & 1u) != 0;  // toggles every second
  const bool di[regs::kDiCount] = {
      s.ready,        s.trigger_ack,          s.busy,           s.result_valid, s.part_ok,
      s.error(),      s.trigger_rejected,     s.scanner_online, heartbeat_bit,  s.plc_comm_lost,
      s.result_stale, live.calibration_drift, s.part_undecided};
  std::uint16_t status_word = 0;
  for (int i = 0; i < regs::kDiCount; ++i) {
    m->tab_input_bits[i] = di[i] ? 1 : 0;
    status_word = static_cast<std::uint16_t>(status_word | bit(di[i], i));
  }
  std::uint16_t* ir = m->tab_input_registers;
  ir[regs::kIrMapVersion] = regs::kMapVersion;
  ir[regs::kIrBootId] = live.boot_id;
  ir[regs::kIrState] = static_cast<std::uint16_t>(s.state);
  ir[regs::kIrHeartbeat] = live.heartbeat;
  ir[regs::kIrErrorCode] = static_cast<std::uint16_t>(s.error_code);
  ir[regs::kIrErrorDetail] = static_cast<std::uint16_t>(s.error_detail);
  ir[regs::kIrTriggerCount] = s.trigger_count;
  put_int32(regs::kIrEndianProbe, regs::kEndianProbeValue);
  ir[regs::kIrStatusWord] = status_word;
  ir[regs::kIrRejectCode] = static_cast<std::uint16_t>(s.reject_code);
  ir[regs::kIrRejectCount] = s.reject_count;
  ir[regs::kIrScanProgress] = live.scan_progress_pct;
  mirror_inputs(0, regs::kLiveCount, regs::kHrLiveMirror);
}

void RegisterImage::publish_result(const ResultBlock& block) {
  std::uint16_t* ir = mapping_->tab_input_registers;
  // RESULT_SEQ goes last: a PLC that compares it before and after its reads sees a change.
  std::fill(ir + regs::kIrResultSeq, ir + regs::kResultBlockEnd, std::uint16_t{0});
  std::fill(ir + regs::kIrVectors, ir + regs::kInputRegisterCount, std::uint16_t{0});
  ir[regs::kIrResultPartId] = block.part_id;
  ir[regs::kIrResultJobId] = block.job_id;
  ir[regs::kIrResultCode] = static_cast<std::uint16_t>(block.code);
  put_int32(regs::kIrMaxDeviation, regs::mm_to_um(block.max_deviation_mm));
  put_int32(regs::kIrRmsDeviation, regs::mm_to_um(block.rms_deviation_mm));
  put_int32(regs::kIrP95Deviation, regs::mm_to_um(block.p95_deviation_mm));
  put_int32(regs::kIrCycleTimeMs,
            static_cast<std::int32_t>(std::clamp<std::int64_t>(block.cycle_time_ms, 0, INT32_MAX)));
  put_int32(regs::kIrScanPoints,
            static_cast<std::int32_t>(std::clamp<std::int64_t>(block.scan_points, 0, INT32_MAX)));
  const auto bends = std::min<std::size_t>(block.bends.size(), regs::kMaxBends);
  ir[regs::kIrBendCount] = static_cast<std::uint16_t>(bends);
  ir[regs::kIrBendRecordSize] = regs::kBendRecordSize;
  std::uint16_t failed = 0, undecided = 0;
  for (std::size_t j = 0; j < bends; ++j) {
    const BendRow& b = block.bends[j];
    const auto base = static_cast<std::uint16_t>(regs::kIrBendTable + j * regs::kBendRecordSize);
    ir[base + regs::kBendId] = b.id;
    ir[base + regs::kBendFlags] = static_cast<std::uint16_t>(
        (b.measured ? regs::kBendMeasured : 0) | (b.pass ? regs::kBendPass : 0) |
        (b.measurable ? 0 : regs::kBendNotMeasurable) | (b.undecided ? regs::kBendUndecided : 0));
    put_int32(static_cast<std::uint16_t>(base + regs::kBendSpringback),
              regs::deg_to_mdeg(b.springback_deg));
    put_int32(static_cast<std::uint16_t>(base + regs::kBendMeasuredAngle),
              regs::deg_to_mdeg(b.measured_angle_deg));
    const auto shape =
        static_cast<std::uint16_t>(regs::kIrBendShapeTable + j * regs::kBendShapeRecordSize);
    put_int32(static_cast<std::uint16_t>(shape + regs::kBendAngleSpread),
              regs::deg_to_mdeg(b.angle_spread_deg));
    put_int32(static_cast<std::uint16_t>(shape + regs::kBendMeasuredRadius),
              regs::mm_to_um(b.measured_radius_mm));
    if (b.measured && !b.pass && !b.undecided) ++failed;
    if (b.undecided) ++undecided;
  }
  ir[regs::kIrBendsFailed] = failed;
  ir[regs::kIrBendsUndecided] = undecided;
  const auto vectors = std::min<std::size_t>(block.vectors.size(), regs::kMaxVectors);
  ir[regs::kIrVectorCount] = static_cast<std::uint16_t>(vectors);
  ir[regs::kIrVectorRecordSize] = regs::kVectorRecordSize;
  for (std::size_t i = 0; i < vectors; ++i) {
    const VectorRow& v = block.vectors[i];
    const auto base = static_cast<std::uint16_t>(regs::kIrVectors + i * regs::kVectorRecordSize);
    bool clipped = false;
    const std::int32_t dx = regs::mm_to_um(v.dx_mm, &clipped);
    const std::int32_t dy = regs::mm_to_um(v.dy_mm, &clipped);
    const std::int32_t dz = regs::mm_to_um(v.dz_mm, &clipped);
    ir[base + regs::kVectorIndex] = static_cast<std::uint16_t>(i);
    ir[base + regs::kVectorFlags] =
        static_cast<std::uint16_t>(regs::kVectorValid | (clipped ? regs::kVectorClipped : 0));
    put_int32(static_cast<std::uint16_t>(base + regs::kVectorDx), dx);
    put_int32(static_cast<std::uint16_t>(base + regs::kVectorDy), dy);
    put_int32(static_cast<std::uint16_t>(base + regs::kVectorDz), dz);
  }
  ir[regs::kIrResultSeq] = block.seq;
  mirror_inputs(regs::kIrResultSeq, regs::kResultBlockEnd - regs::kIrResultSeq, regs::kIrResultSeq);
  mirror_inputs(regs::kIrVectors, regs::kInputRegisterCount - regs::kIrVectors, regs::kIrVectors);
  refresh_window();
}

void RegisterImage::refresh_window() {
  std::uint16_t* ir = mapping_->tab_input_registers;
  const std::uint16_t page = mapping_->tab_registers[regs::kHrPageSelect];
  constexpr std::uint16_t kWords = regs::kWindowRecordsPerPage * regs::kVectorRecordSize;
  ir[regs::kIrWindowPage] = page;
  ir[regs::kIrWindowSeq] = ir[regs::kIrResultSeq];
  const std::size_t first = regs::kIrVectors + std::size_t{page} * kWords;
  for (std::uint16_t k = 0; k < kWords; ++k) {
    const std::size_t from = first + k;
    // Pages past the block show zeros (flags 0 = no vector), not an exception.
    ir[regs::kIrWindowRecords + k] = from < regs::kInputRegisterCount ? ir[from] : 0;
  }
  mirror_inputs(regs::kIrWindowPage, regs::kWindowEnd - regs::kIrWindowPage, regs::kIrWindowPage);
}

std::uint16_t RegisterImage::input_register(std::uint16_t address) const {
  return address < regs::kInputRegisterCount ? mapping_->tab_input_registers[address] : 0;
}

std::uint16_t RegisterImage::holding_register(std::uint16_t address) const {
  return address < regs::kInputRegisterCount ? mapping_->tab_registers[address] : 0;
}

bool RegisterImage::discrete_input(std::uint16_t address) const {
  return address < regs::kDiCount && mapping_->tab_input_bits[address] != 0;
}

void RegisterImage::put_int32(std::uint16_t address, std::int32_t value) {
  regs::encode_int32(value, order_, mapping_->tab_input_registers + address);
}

void RegisterImage::mirror_inputs(std::uint16_t first, std::uint16_t count,
                                  std::uint16_t holding_first) {
  std::copy_n(mapping_->tab_input_registers + first, count,
              mapping_->tab_registers + holding_first);
}

}  // namespace springscan::daemon
