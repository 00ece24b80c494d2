#include "daemon/register_map.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "daemon/register_image.hpp"
#include "daemon/result_block.hpp"

namespace springscan::daemon {
namespace {

using regs::WordOrder;

TEST(Int32Encoding, EndianProbeInBothWordOrders) {
  std::uint16_t words[2];
  regs::encode_int32(regs::kEndianProbeValue, WordOrder::kAbcd, words);
  EXPECT_EQ(words[0], 0x0102);
  EXPECT_EQ(words[1], 0x0304);
  regs::encode_int32(regs::kEndianProbeValue, WordOrder::kCdab, words);
  EXPECT_EQ(words[0], 0x0304);
  EXPECT_EQ(words[1], 0x0102);
}

TEST(Int32Encoding, RoundTripsNegativeAndExtremeValues) {
  for (const std::int32_t value : {0, 1, -1, -123456, 2147483647, -2147483647 - 1}) {
    for (const WordOrder order : {WordOrder::kAbcd, WordOrder::kCdab}) {
      std::uint16_t words[2];
      regs::encode_int32(value, order, words);
      EXPECT_EQ(regs::decode_int32(words, order), value);
    }
  }
  std::uint16_t words[2];
  regs::encode_int32(-2, WordOrder::kAbcd, words);  // two's complement: 0xFFFFFFFE
  EXPECT_EQ(words[0], 0xFFFF);
  EXPECT_EQ(words[1], 0xFFFE);
}

TEST(Scaling, MillimetresToMicrometresRoundsAndSaturates) {
  EXPECT_EQ(regs::mm_to_um(1.2345), 1235);  // rounds to nearest (1234.5 -> 1235)
  EXPECT_EQ(regs::mm_to_um(-0.0004), 0);
  EXPECT_EQ(regs::mm_to_um(-0.0006), -1);
  EXPECT_EQ(regs::mm_to_um(-2.5), -2500);
  bool clipped = false;
  EXPECT_EQ(regs::mm_to_um(1e9, &clipped), std::numeric_limits<std::int32_t>::max());
  EXPECT_TRUE(clipped);
  EXPECT_EQ(regs::mm_to_um(std::nan("")), regs::kInvalidInt32);
  EXPECT_EQ(regs::deg_to_mdeg(-1.5), -1500);
}

TEST(ResultSeq, NeverZeroAndWraps) {
  EXPECT_EQ(regs::result_seq_from_record(1), 1);
  EXPECT_EQ(regs::result_seq_from_record(65535), 65535);
  EXPECT_EQ(regs::result_seq_from_record(65536), 1);
  EXPECT_EQ(regs::result_seq_from_record(131070), 65535);
}

ResultBlock example_block() {
  ResultBlock block;
  block.seq = 42;
  block.part_id = 3;
  block.job_id = 77;
  block.code = regs::ResultCode::kFormNok;
  block.max_deviation_mm = 0.8125;
  block.rms_deviation_mm = 0.25;
  block.p95_deviation_mm = 0.5;
  block.cycle_time_ms = 1234;
  block.scan_points = 200000;
  block.bends = {{1, true, true, 0.5, 89.5}, {2, true, false, -2.25, 92.25}};
  block.bends[0].angle_spread_deg = 0.0425;
  block.bends[0].measured_radius_mm = 3.0125;
  BendRow hem{3, false, true, 0.0, 0.0};
  hem.measurable = false;
  block.bends.push_back(hem);
  for (int i = 0; i < 300; ++i) {
    block.vectors.push_back({0.001 * i, -0.002 * i, 0.5});
  }
  return block;
}

class RegisterImageTest : public ::testing::TestWithParam<WordOrder> {};

TEST_P(RegisterImageTest, ResultBlockEncodesEveryField) {
  const WordOrder order = GetParam();
  RegisterImage image(order);
  image.publish_result(example_block());
  const auto ir = [&](std::uint16_t a) { return image.input_register(a); };
  const auto i32 = [&](std::uint16_t a) {
    const std::uint16_t w[2] = {ir(a), ir(static_cast<std::uint16_t>(a + 1))};
    return regs::decode_int32(w, order);
  };
  EXPECT_EQ(ir(regs::kIrResultSeq), 42);
  EXPECT_EQ(ir(regs::kIrResultPartId), 3);
  EXPECT_EQ(ir(regs::kIrResultJobId), 77);
  EXPECT_EQ(ir(regs::kIrResultCode), 1);
  EXPECT_EQ(i32(regs::kIrMaxDeviation), 813);  // 812.5 rounds away from zero
  EXPECT_EQ(i32(regs::kIrRmsDeviation), 250);
  EXPECT_EQ(i32(regs::kIrP95Deviation), 500);
  EXPECT_EQ(i32(regs::kIrCycleTimeMs), 1234);
  EXPECT_EQ(i32(regs::kIrScanPoints), 200000);
  EXPECT_EQ(ir(regs::kIrVectorCount), 300);
  EXPECT_EQ(ir(regs::kIrVectorRecordSize), 8);
  EXPECT_EQ(ir(regs::kIrBendCount), 3);
  EXPECT_EQ(ir(regs::kIrBendsFailed), 1);
  EXPECT_EQ(ir(regs::kIrBendsUndecided), 0);  // register 119 (reserved before map version 6)
  const std::uint16_t bend2 = regs::kIrBendTable + regs::kBendRecordSize;
  EXPECT_EQ(ir(bend2 + regs::kBendId), 2);
  EXPECT_EQ(ir(bend2 + regs::kBendFlags), regs::kBendMeasured);
  EXPECT_EQ(i32(bend2 + regs::kBendSpringback), -2250);
  EXPECT_EQ(i32(bend2 + regs::kBendMeasuredAngle), 92250);
  // The bend shape table (map version 3) after the 16 bend records, one record per bend.
  EXPECT_EQ(regs::kIrBendShapeTable, 216);
  EXPECT_EQ(i32(regs::kIrBendShapeTable + regs::kBendAngleSpread), 43);  // 42.5 m° rounds up
  EXPECT_EQ(i32(regs::kIrBendShapeTable + regs::kBendMeasuredRadius), 3013);
  const std::uint16_t shape2 = regs::kIrBendShapeTable + regs::kBendShapeRecordSize;
  EXPECT_EQ(i32(shape2 + regs::kBendAngleSpread), regs::kInvalidInt32);  // no stations
  EXPECT_EQ(i32(shape2 + regs::kBendMeasuredRadius), regs::kInvalidInt32);
  const std::uint16_t bend3 = regs::kIrBendTable + 2 * regs::kBendRecordSize;
  EXPECT_EQ(ir(bend3 + regs::kBendFlags), regs::kBendPass | regs::kBendNotMeasurable);
  const std::uint16_t v299 = regs::kIrVectors + 299 * regs::kVectorRecordSize;
  EXPECT_EQ(ir(v299 + regs::kVectorIndex), 299);
  EXPECT_EQ(ir(v299 + regs::kVectorFlags), regs::kVectorValid);
  EXPECT_EQ(i32(v299 + regs::kVectorDx), 299);
  EXPECT_EQ(i32(v299 + regs::kVectorDy), -598);
  EXPECT_EQ(i32(v299 + regs::kVectorDz), 500);
  EXPECT_EQ(ir(v299 + regs::kVectorRecordSize + regs::kVectorFlags), 0);  // past N: empty
  // The FC03 mirror holds the same words.
  EXPECT_EQ(image.holding_register(v299 + regs::kVectorDy + 1), ir(v299 + regs::kVectorDy + 1));
  EXPECT_EQ(image.holding_register(regs::kIrResultSeq), 42);
}

TEST_P(RegisterImageTest, WindowShowsTheSelectedPage) {
  RegisterImage image(GetParam());
  image.publish_result(example_block());
  image.mapping()->tab_registers[regs::kHrPageSelect] = 2;  // records 30..44
  image.refresh_window();
  EXPECT_EQ(image.input_register(regs::kIrWindowPage), 2);
  EXPECT_EQ(image.input_register(regs::kIrWindowSeq), 42);
  EXPECT_EQ(image.input_register(regs::kIrWindowRecords + regs::kVectorIndex), 30);
  EXPECT_EQ(image.input_register(regs::kIrWindowRecords + 14 * 8 + regs::kVectorIndex), 44);
  image.mapping()->tab_registers[regs::kHrPageSelect] = 65535;  // far past the block: zeros
  image.refresh_window();
  EXPECT_EQ(image.input_register(regs::kIrWindowRecords + regs::kVectorFlags), 0);
}

TEST_P(RegisterImageTest, StatusBitsWordAndLiveBlock) {
  RegisterImage image(GetParam());
  MachineStatus s;
  s.state = regs::State::kDone;
  s.ready = false;
  s.result_valid = true;
  s.part_ok = true;
  s.scanner_online = true;
  s.trigger_count = 9;
  s.reject_code = regs::RejectCode::kBusy;
  image.publish_status(s, LiveValues{4321, 15, 0});
  EXPECT_TRUE(image.discrete_input(regs::kDiResultValid));
  EXPECT_TRUE(image.discrete_input(regs::kDiPartOk));
  EXPECT_FALSE(image.discrete_input(regs::kDiReady));
  EXPECT_TRUE(image.discrete_input(regs::kDiHeartbeat));  // 15 / 10 is odd
  EXPECT_EQ(image.input_register(regs::kIrStatusWord),
            (1u << regs::kDiResultValid) | (1u << regs::kDiPartOk) |
                (1u << regs::kDiScannerOnline) | (1u << regs::kDiHeartbeat));
  EXPECT_EQ(image.input_register(regs::kIrBootId), 4321);
  EXPECT_EQ(image.input_register(regs::kIrState), 6);
  EXPECT_EQ(image.input_register(regs::kIrMapVersion), regs::kMapVersion);
  EXPECT_EQ(image.input_register(regs::kIrRejectCode), 1);
  EXPECT_EQ(image.holding_register(regs::kHrLiveMirror + regs::kIrTriggerCount), 9);
  const std::uint16_t probe[2] = {image.input_register(regs::kIrEndianProbe),
                                  image.input_register(regs::kIrEndianProbe + 1)};
  EXPECT_EQ(regs::decode_int32(probe, GetParam()), regs::kEndianProbeValue);
}

TEST_P(RegisterImageTest, ControlWordAndCoilsAreOred) {
  RegisterImage image(GetParam());
  modbus_mapping_t* m = image.mapping();
  m->tab_bits[regs::kCoilTriggerEnable] = 1;
  m->tab_registers[regs::kHrControlWord] = 1u << regs::kCoilTrigger;
  m->tab_registers[regs::kHrJobId] = 5;
  m->tab_registers[regs::kHrPartId] = 6;
  regs::encode_int32(20261207, GetParam(), &m->tab_registers[regs::kHrPartSerial]);
  const PlcControl plc = image.plc_control();
  EXPECT_TRUE(plc.trigger_enable);
  EXPECT_TRUE(plc.trigger);
  EXPECT_FALSE(plc.result_ack);
  EXPECT_FALSE(plc.error_reset);
  EXPECT_EQ(plc.job_id, 5);
  EXPECT_EQ(plc.part_id, 6);
  EXPECT_EQ(plc.part_serial, 20261207u);  // in the map's word order, as every 32-bit value
}

TEST_P(RegisterImageTest, TriggerSetThroughControlWordDropsWhenItsBitIsCleared) {
  RegisterImage image(GetParam());
  modbus_mapping_t* m = image.mapping();
  m->tab_registers[regs::kHrControlWord] = 0b011;  // TRIGGER_ENABLE + TRIGGER
  EXPECT_TRUE(image.plc_control().trigger);
  m->tab_registers[regs::kHrControlWord] = 0b001;  // drop TRIGGER, keep TRIGGER_ENABLE
  EXPECT_FALSE(image.plc_control().trigger);
  EXPECT_TRUE(image.plc_control().trigger_enable);
  m->tab_bits[regs::kCoilTrigger] = 1;  // a coil left high keeps TRIGGER high whatever the word
  EXPECT_TRUE(image.plc_control().trigger);
}

TEST_P(RegisterImageTest, LastPageShowsTheLastRecordsOfAFullBlock) {
  RegisterImage image(GetParam());
  ResultBlock block = example_block();
  block.vectors.resize(regs::kMaxVectors, VectorRow{0.001, 0.0, 0.0});
  image.publish_result(block);
  image.mapping()->tab_registers[regs::kHrPageSelect] = regs::kPageCount - 1;  // 68
  image.refresh_window();
  EXPECT_EQ(image.input_register(regs::kIrWindowRecords + regs::kVectorIndex), 1020);
  EXPECT_EQ(image.input_register(regs::kIrWindowRecords + 3 * 8 + regs::kVectorIndex), 1023);
  EXPECT_EQ(image.input_register(regs::kIrWindowRecords + 4 * 8 + regs::kVectorFlags), 0);
}

TEST_P(RegisterImageTest, StaleResultIsDiscreteInputTenAndStatusWordBitTen) {
  RegisterImage image(GetParam());
  MachineStatus s;
  s.result_valid = true;
  s.result_stale = true;
  image.publish_status(s, LiveValues{});
  EXPECT_TRUE(image.discrete_input(regs::kDiResultStale));
  EXPECT_TRUE(image.discrete_input(regs::kDiResultValid));
  EXPECT_EQ(image.input_register(regs::kIrStatusWord), (1u << 10) | (1u << 3));
}

// Map version 6: an UNDECIDED result is RESULT_CODE 6, PART_UNDECIDED (discrete input 12,
// status word bit 12) and never PART_OK; its bends carry the UNDECIDED flag and are counted at
// 119, apart from the failed ones at 114.
TEST_P(RegisterImageTest, AnUndecidedResultIsNeverPartOk) {
  EXPECT_EQ(regs::kMapVersion, 6);
  EXPECT_EQ(static_cast<int>(regs::ResultCode::kUndecided), 6);
  EXPECT_EQ(regs::kDiPartUndecided, 12);
  EXPECT_EQ(regs::kIrBendsUndecided, 119);
  RegisterImage image(GetParam());
  ResultBlock block = example_block();
  block.code = regs::ResultCode::kUndecided;
  block.bends[0].pass = false;  // within U of its tolerance
  block.bends[0].undecided = true;
  BendRow unseen{5, false, false, 0.0, 0.0};  // not measured: undecided too
  unseen.undecided = true;
  block.bends.push_back(unseen);
  image.publish_result(block);
  const auto ir = [&](std::uint16_t a) { return image.input_register(a); };
  EXPECT_EQ(ir(regs::kIrResultCode), 6);
  EXPECT_EQ(ir(regs::kIrBendsFailed), 1);  // bend 2 only
  EXPECT_EQ(ir(regs::kIrBendsUndecided), 2);
  EXPECT_EQ(ir(regs::kIrBendTable + regs::kBendFlags), regs::kBendMeasured | regs::kBendUndecided);
  EXPECT_EQ(ir(regs::kIrBendTable + 3 * regs::kBendRecordSize + regs::kBendFlags),
            regs::kBendUndecided);
  MachineStatus s;
  s.result_valid = true;
  s.part_undecided = true;
  image.publish_status(s, LiveValues{});
  EXPECT_TRUE(image.discrete_input(regs::kDiPartUndecided));
  EXPECT_FALSE(image.discrete_input(regs::kDiPartOk));
  EXPECT_EQ(image.input_register(regs::kIrStatusWord), (1u << 12) | (1u << 3));
  EXPECT_EQ(image.holding_register(regs::kHrLiveMirror + regs::kIrStatusWord),
            (1u << 12) | (1u << 3));
}

// The report's decisions reach the block: RESULT_CODE 6 is an analysed result, each bend's
// UNDECIDED decision its flag.
TEST(ResultBlockFromReport, AnUndecidedReportKeepsItsCodeAndBendDecisions) {
  v1::InspectionReport report;
  report.set_result_seq(8);
  report.set_result_code(static_cast<std::uint32_t>(regs::ResultCode::kUndecided));
  report.mutable_deviation()->set_max(0.3);
  auto* bend = report.add_bends();
  bend->set_measured(true);
  bend->set_decision(v1::UNDECIDED);
  report.add_bends()->set_decision(v1::CONFORMING);
  const ResultBlock block = result_block_from_report(report);
  EXPECT_EQ(block.code, regs::ResultCode::kUndecided);
  EXPECT_DOUBLE_EQ(block.max_deviation_mm, 0.3) << "analysed: the figures are shown";
  ASSERT_EQ(block.bends.size(), 2u);
  EXPECT_TRUE(block.bends[0].undecided);
  EXPECT_FALSE(block.bends[1].undecided);
}

INSTANTIATE_TEST_SUITE_P(WordOrders, RegisterImageTest,
                         ::testing::Values(WordOrder::kAbcd, WordOrder::kCdab));

TEST(ResultBlockFromReport, FailedScanShowsInvalidDeviations) {
  v1::InspectionReport report;
  report.set_result_seq(5);
  report.set_result_code(static_cast<std::uint32_t>(regs::ResultCode::kScanFailed));
  report.mutable_input()->set_part_id("12");
  report.mutable_deviation()->set_max(0.3);  // ignored: there was no analysis
  const ResultBlock block = result_block_from_report(report);
  EXPECT_EQ(block.part_id, 12);
  EXPECT_EQ(block.code, regs::ResultCode::kScanFailed);
  EXPECT_EQ(regs::mm_to_um(block.max_deviation_mm), regs::kInvalidInt32);
}

TEST(ResultBlockFromReport, MaxDevIsAMagnitudeEvenWhenTheLargestDeviationIsNegative) {
  v1::InspectionReport report;
  report.set_result_seq(7);
  report.set_result_code(1);
  report.mutable_deviation()->set_min(-0.9);
  report.mutable_deviation()->set_max(0.3);
  RegisterImage image(WordOrder::kAbcd);
  image.publish_result(result_block_from_report(report));
  const std::uint16_t w[2] = {image.input_register(regs::kIrMaxDeviation),
                              image.input_register(regs::kIrMaxDeviation + 1)};
  EXPECT_EQ(regs::decode_int32(w, WordOrder::kAbcd), 900);
}

TEST(ResultBlockFromReport, AnalysedReportKeepsLargestMagnitudeAndBends) {
  v1::InspectionReport report;
  report.set_result_seq(6);
  report.set_result_code(0);
  report.mutable_deviation()->set_min(-1.5);
  report.mutable_deviation()->set_max(0.7);
  auto* bend = report.add_bends();
  bend->set_id(4);
  bend->set_springback_deg(1.25);
  bend->set_measured(true);
  bend->set_pass(true);
  auto* c = report.add_compensation();
  c->mutable_vector()->set_z(-0.1);
  const ResultBlock block = result_block_from_report(report);
  EXPECT_DOUBLE_EQ(block.max_deviation_mm, 1.5);
  ASSERT_EQ(block.bends.size(), 1u);
  EXPECT_EQ(block.bends[0].id, 4);
  EXPECT_DOUBLE_EQ(block.bends[0].springback_deg, 1.25);
  ASSERT_EQ(block.vectors.size(), 1u);
  EXPECT_DOUBLE_EQ(block.vectors[0].dz_mm, -0.1);
}

}  // namespace
}  // namespace springscan::daemon
