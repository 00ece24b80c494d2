#include "daemon/request_check.hpp"

#include <gtest/gtest.h>
#include <modbus/modbus.h>

#include <vector>

#include "daemon/register_map.hpp"

namespace springscan::daemon {
namespace {

/// An ADU: MBAP (tid 0x1234, protocol 0, length, unit) + PDU.
std::vector<std::uint8_t> adu(std::vector<std::uint8_t> pdu, std::uint8_t unit = 1) {
  const std::size_t length = pdu.size() + 1;
  std::vector<std::uint8_t> out = {0x12,
                                   0x34,
                                   0,
                                   0,
                                   static_cast<std::uint8_t>(length >> 8),
                                   static_cast<std::uint8_t>(length & 0xFF),
                                   unit};
  for (const std::uint8_t byte : pdu) out.push_back(byte);  // (insert trips GCC 12 -Warray-bounds)
  return out;
}

std::vector<std::uint8_t> read_pdu(std::uint8_t fc, std::uint16_t address, std::uint16_t count) {
  return {fc, static_cast<std::uint8_t>(address >> 8), static_cast<std::uint8_t>(address),
          static_cast<std::uint8_t>(count >> 8), static_cast<std::uint8_t>(count)};
}

int verdict(const std::vector<std::uint8_t>& frame) {
  return check_request(frame.data(), frame.size()).exception;
}

TEST(MbapPrefix, RejectsForeignProtocolAndBadLengths) {
  const std::uint8_t good[] = {0, 1, 0, 0, 0, 6};
  EXPECT_TRUE(check_mbap_prefix(good, 6).valid);
  EXPECT_EQ(check_mbap_prefix(good, 6).frame_bytes, 12u);
  const std::uint8_t foreign[] = {0, 1, 0, 1, 0, 6};
  EXPECT_FALSE(check_mbap_prefix(foreign, 6).valid);
  const std::uint8_t zero[] = {0, 1, 0, 0, 0, 0};
  EXPECT_FALSE(check_mbap_prefix(zero, 6).valid);
  const std::uint8_t huge[] = {0, 1, 0, 0, 1, 0};  // 256 > 254
  EXPECT_FALSE(check_mbap_prefix(huge, 6).valid);
  EXPECT_FALSE(check_mbap_prefix(good, 5).valid);
}

TEST(RequestCheck, AcceptsEveryServedFunctionInsideTheMap) {
  EXPECT_EQ(verdict(adu(read_pdu(1, 0, 4))), 0);
  EXPECT_EQ(verdict(adu(read_pdu(2, 0, 10))), 0);
  EXPECT_EQ(verdict(adu(read_pdu(3, 0, 5))), 0);
  EXPECT_EQ(verdict(adu(read_pdu(3, regs::kHrLiveMirror, regs::kLiveCount))), 0);
  EXPECT_EQ(verdict(adu(read_pdu(4, 0, regs::kLiveCount))), 0);
  EXPECT_EQ(verdict(adu(read_pdu(4, regs::kIrResultSeq, 116))), 0);
  EXPECT_EQ(verdict(adu(read_pdu(4, regs::kInputRegisterCount - 120, 120))), 0);
  EXPECT_EQ(verdict(adu({5, 0, 1, 0xFF, 0})), 0);
  EXPECT_EQ(verdict(adu({6, 0, 2, 0, 9})), 0);
  EXPECT_EQ(verdict(adu({15, 0, 0, 0, 4, 1, 0x0F})), 0);
  EXPECT_EQ(verdict(adu({16, 0, 1, 0, 2, 4, 0, 7, 0, 3})), 0);
  EXPECT_EQ(verdict(adu(read_pdu(4, 0, 1), 0xFF)), 0);  // "no unit" of Modbus TCP
}

TEST(RequestCheck, IllegalFunction) {
  EXPECT_EQ(verdict(adu({23, 0, 0, 0, 1, 0, 0, 0, 1, 2, 0, 0})), MODBUS_EXCEPTION_ILLEGAL_FUNCTION);
  EXPECT_EQ(verdict(adu({0x11})), MODBUS_EXCEPTION_ILLEGAL_FUNCTION);
  EXPECT_EQ(verdict(adu({0x07})), MODBUS_EXCEPTION_ILLEGAL_FUNCTION);
  EXPECT_EQ(verdict(adu({0x2B, 0x0E, 1, 0})), MODBUS_EXCEPTION_ILLEGAL_FUNCTION);
}

TEST(RequestCheck, IllegalDataAddress) {
  EXPECT_EQ(verdict(adu(read_pdu(1, 3, 2))), MODBUS_EXCEPTION_ILLEGAL_DATA_ADDRESS);
  EXPECT_EQ(verdict(adu(read_pdu(2, regs::kDiCount, 1))), MODBUS_EXCEPTION_ILLEGAL_DATA_ADDRESS);
  EXPECT_EQ(verdict(adu(read_pdu(4, regs::kLiveCount, 1))), MODBUS_EXCEPTION_ILLEGAL_DATA_ADDRESS);
  // A read spanning two blocks touches the gap between them.
  EXPECT_EQ(verdict(adu(read_pdu(4, regs::kWindowEnd - 1, 100))),
            MODBUS_EXCEPTION_ILLEGAL_DATA_ADDRESS);
  EXPECT_EQ(verdict(adu(read_pdu(4, regs::kInputRegisterCount - 1, 2))),
            MODBUS_EXCEPTION_ILLEGAL_DATA_ADDRESS);
  EXPECT_EQ(verdict(adu(read_pdu(4, 0xFFFF, 1))), MODBUS_EXCEPTION_ILLEGAL_DATA_ADDRESS);
  // Writes to read-only areas: the FC03 mirrors and past the PLC's registers.
  EXPECT_EQ(verdict(adu({6, 0, regs::kHrLiveMirror, 0, 1})), MODBUS_EXCEPTION_ILLEGAL_DATA_ADDRESS);
  EXPECT_EQ(verdict(adu({6, 0, regs::kIrResultSeq, 0, 1})), MODBUS_EXCEPTION_ILLEGAL_DATA_ADDRESS);
  // Two registers from the last writable one (PART_SERIAL's low word) reach past it.
  constexpr auto last = static_cast<std::uint8_t>(regs::kHrWritableCount - 1);
  EXPECT_EQ(verdict(adu({16, 0, last, 0, 2, 4, 0, 0, 0, 0})),
            MODBUS_EXCEPTION_ILLEGAL_DATA_ADDRESS);
  EXPECT_EQ(verdict(adu({16, 0, regs::kHrPartSerial, 0, 2, 4, 0, 1, 0, 2})), 0);  // PART_SERIAL
  EXPECT_EQ(verdict(adu({5, 0, 4, 0xFF, 0})), MODBUS_EXCEPTION_ILLEGAL_DATA_ADDRESS);
  EXPECT_EQ(verdict(adu({15, 0, 2, 0, 3, 1, 7})), MODBUS_EXCEPTION_ILLEGAL_DATA_ADDRESS);
}

TEST(RequestCheck, IllegalDataValueForCountsAndLengths) {
  EXPECT_EQ(verdict(adu(read_pdu(4, 1000, 0))), MODBUS_EXCEPTION_ILLEGAL_DATA_VALUE);
  EXPECT_EQ(verdict(adu(read_pdu(4, 1000, 126))), MODBUS_EXCEPTION_ILLEGAL_DATA_VALUE);
  EXPECT_EQ(verdict(adu(read_pdu(1, 0, 2001))), MODBUS_EXCEPTION_ILLEGAL_DATA_VALUE);
  EXPECT_EQ(verdict(adu({5, 0, 1, 0x12, 0x34})), MODBUS_EXCEPTION_ILLEGAL_DATA_VALUE);
  EXPECT_EQ(verdict(adu({3, 0, 0, 0})), MODBUS_EXCEPTION_ILLEGAL_DATA_VALUE);        // short
  EXPECT_EQ(verdict(adu({3, 0, 0, 0, 1, 9})), MODBUS_EXCEPTION_ILLEGAL_DATA_VALUE);  // long
  EXPECT_EQ(verdict(adu({3})), MODBUS_EXCEPTION_ILLEGAL_DATA_VALUE);
  // FC16: byte count disagreeing with the quantity, or with the bytes present.
  EXPECT_EQ(verdict(adu({16, 0, 1, 0, 2, 2, 0, 7})), MODBUS_EXCEPTION_ILLEGAL_DATA_VALUE);
  EXPECT_EQ(verdict(adu({16, 0, 1, 0, 2, 4, 0, 7})), MODBUS_EXCEPTION_ILLEGAL_DATA_VALUE);
  EXPECT_EQ(verdict(adu({16, 0, 1, 0, 124, 248})), MODBUS_EXCEPTION_ILLEGAL_DATA_VALUE);
  EXPECT_EQ(verdict(adu({15, 0, 0, 0, 4, 2, 7, 0})), MODBUS_EXCEPTION_ILLEGAL_DATA_VALUE);
  EXPECT_EQ(verdict(adu({15, 0, 0})), MODBUS_EXCEPTION_ILLEGAL_DATA_VALUE);
}

TEST(RequestCheck, OtherUnitIdIsAGatewayTargetException) {
  EXPECT_EQ(verdict(adu(read_pdu(4, 0, 1), 9)), MODBUS_EXCEPTION_GATEWAY_TARGET);
  RequestCheckSettings settings;
  settings.unit_id = 9;
  const auto frame = adu(read_pdu(4, 0, 1), 9);
  EXPECT_EQ(check_request(frame.data(), frame.size(), settings).exception, 0);
}

TEST(RequestCheck, UnitIdZeroIsAnsweredLikeTheNoUnitValue) {
  // pymodbus and other TCP clients send unit id 0 unless told otherwise.
  EXPECT_EQ(verdict(adu(read_pdu(4, 0, 1), 0)), 0);
  RequestCheckSettings settings;
  settings.unit_id = 9;
  const auto frame = adu(read_pdu(4, 0, 1), 0);
  EXPECT_EQ(check_request(frame.data(), frame.size(), settings).exception, 0);
}

TEST(RequestCheck, PageSelectPastTheLastPageIsAnIllegalValue) {
  const auto last = static_cast<std::uint8_t>(regs::kPageCount - 1);  // 68: records 1020..1023
  EXPECT_EQ(regs::kPageCount, 69);
  EXPECT_EQ(verdict(adu({6, 0, 4, 0, last})), 0);
  EXPECT_EQ(verdict(adu({6, 0, 4, 0, 69})), MODBUS_EXCEPTION_ILLEGAL_DATA_VALUE);
  EXPECT_EQ(verdict(adu({6, 0, 4, 0xFF, 0xFF})), MODBUS_EXCEPTION_ILLEGAL_DATA_VALUE);
  // FC16 over 1..4 with PAGE_SELECT last: the whole write is refused, also when it starts at 4.
  EXPECT_EQ(verdict(adu({16, 0, 1, 0, 4, 8, 0, 7, 0, 1, 0, 2, 0, last})), 0);
  EXPECT_EQ(verdict(adu({16, 0, 1, 0, 4, 8, 0, 7, 0, 1, 0, 2, 0, 70})),
            MODBUS_EXCEPTION_ILLEGAL_DATA_VALUE);
  EXPECT_EQ(verdict(adu({16, 0, 4, 0, 1, 2, 1, 0})), MODBUS_EXCEPTION_ILLEGAL_DATA_VALUE);
  // Other holding registers take any value; a write that does not reach 4 is not checked.
  EXPECT_EQ(verdict(adu({16, 0, 1, 0, 3, 6, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF})), 0);
}

TEST(RequestCheck, FrameLengthMustMatchMbap) {
  auto frame = adu(read_pdu(4, 0, 1));
  frame.push_back(0);  // one byte more than MBAP says
  EXPECT_NE(verdict(frame), 0);
}

}  // namespace
}  // namespace springscan::daemon
