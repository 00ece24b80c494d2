#include "daemon/request_check.hpp"

#include <modbus/modbus.h>

#include <array>

#include "daemon/register_map.hpp"

namespace springscan::daemon {

namespace {

struct Block {
  std::uint32_t first;
  std::uint32_t end;  // one past the last address
};

constexpr std::array<Block, 1> kCoils = {{{0, regs::kCoilCount}}};
constexpr std::array<Block, 1> kDiscreteInputs = {{{0, regs::kDiCount}}};
constexpr std::array<Block, 1> kWritableHolding = {{{0, regs::kHrWritableCount}}};
constexpr std::array<Block, 4> kInputRegisters = {{{0, regs::kLiveCount},
                                                   {regs::kIrResultSeq, regs::kResultBlockEnd},
                                                   {regs::kIrWindowPage, regs::kWindowEnd},
                                                   {regs::kIrVectors, regs::kInputRegisterCount}}};
constexpr std::array<Block, 5> kReadableHolding = {
    {{0, regs::kHrWritableCount},
     {regs::kHrLiveMirror, regs::kHrLiveMirror + regs::kLiveCount},
     {regs::kIrResultSeq, regs::kResultBlockEnd},
     {regs::kIrWindowPage, regs::kWindowEnd},
     {regs::kIrVectors, regs::kInputRegisterCount}}};

template <std::size_t N>
bool inside(const std::array<Block, N>& blocks, std::uint32_t first, std::uint32_t count) {
  for (const Block& b : blocks) {
    if (first >= b.first && first + count <= b.end) return true;
  }
  return false;
}

std::uint32_t word(const std::uint8_t* p) {
  return (std::uint32_t{p[0]} << 8) | std::uint32_t{p[1]};
}

RequestVerdict refuse(int exception, std::string problem) {
  return RequestVerdict{exception, std::move(problem)};
}

// A write of PAGE_SELECT past the last page is refused with 03 (the value check comes after the
// address check, as in the spec's state diagrams); nothing of the request is written.
RequestVerdict check_page_select(const std::uint8_t* pdu, int function, std::uint32_t address,
                                 std::uint32_t count) {
  const std::uint8_t* value = nullptr;
  if (function == MODBUS_FC_WRITE_SINGLE_REGISTER && address == regs::kHrPageSelect) {
    value = pdu + 3;
  } else if (function == MODBUS_FC_WRITE_MULTIPLE_REGISTERS && address <= regs::kHrPageSelect &&
             regs::kHrPageSelect < address + count) {
    value = pdu + 6 + 2 * (regs::kHrPageSelect - address);
  }
  if (value != nullptr && word(value) >= regs::kPageCount) {
    return refuse(MODBUS_EXCEPTION_ILLEGAL_DATA_VALUE,
                  "PAGE_SELECT " + std::to_string(word(value)) + " (pages are 0.." +
                      std::to_string(regs::kPageCount - 1) + ")");
  }
  return {};
}

// Quantity limits of the Modbus Application Protocol V1.1b3, sections 6.1-6.4, 6.11, 6.12.
// One switch over the function codes, kept whole (about 65 lines) so it reads as the spec's table.
RequestVerdict check_pdu(const std::uint8_t* pdu, std::size_t pdu_size) {
  const int function = pdu[0];
  const bool bit_write = function == MODBUS_FC_WRITE_MULTIPLE_COILS;
  const bool register_write = function == MODBUS_FC_WRITE_MULTIPLE_REGISTERS;
  if (!bit_write && !register_write && pdu_size != 5) {
    return refuse(MODBUS_EXCEPTION_ILLEGAL_DATA_VALUE,
                  "PDU of function " + std::to_string(function) + " has " +
                      std::to_string(pdu_size) + " bytes, expected 5");
  }
  if ((bit_write || register_write) && pdu_size < 6) {
    return refuse(MODBUS_EXCEPTION_ILLEGAL_DATA_VALUE, "truncated write request");
  }
  const std::uint32_t address = word(pdu + 1);
  std::uint32_t count = 1;
  switch (function) {
    case MODBUS_FC_READ_COILS:
    case MODBUS_FC_READ_DISCRETE_INPUTS:
      count = word(pdu + 3);
      if (count < 1 || count > MODBUS_MAX_READ_BITS) {
        return refuse(MODBUS_EXCEPTION_ILLEGAL_DATA_VALUE, "bit count " + std::to_string(count));
      }
      break;
    case MODBUS_FC_READ_HOLDING_REGISTERS:
    case MODBUS_FC_READ_INPUT_REGISTERS:
      count = word(pdu + 3);
      if (count < 1 || count > MODBUS_MAX_READ_REGISTERS) {
        return refuse(MODBUS_EXCEPTION_ILLEGAL_DATA_VALUE,
                      "register count " + std::to_string(count));
      }
      break;
    case MODBUS_FC_WRITE_SINGLE_COIL: {
      const std::uint32_t value = word(pdu + 3);
      if (value != 0x0000 && value != 0xFF00) {
        return refuse(MODBUS_EXCEPTION_ILLEGAL_DATA_VALUE, "coil value " + std::to_string(value));
      }
      break;
    }
    case MODBUS_FC_WRITE_SINGLE_REGISTER:
      break;
    case MODBUS_FC_WRITE_MULTIPLE_COILS:
    case MODBUS_FC_WRITE_MULTIPLE_REGISTERS: {
      count = word(pdu + 3);
      const std::size_t byte_count = pdu[5];
      const std::uint32_t limit = bit_write ? MODBUS_MAX_WRITE_BITS : MODBUS_MAX_WRITE_REGISTERS;
      const std::size_t expected_bytes = bit_write ? (count + 7) / 8 : std::size_t{count} * 2;
      if (count < 1 || count > limit || byte_count != expected_bytes ||
          pdu_size != 6 + byte_count) {
        return refuse(MODBUS_EXCEPTION_ILLEGAL_DATA_VALUE,
                      "write of " + std::to_string(count) + " with byte count " +
                          std::to_string(byte_count) + " in a " + std::to_string(pdu_size) +
                          "-byte PDU");
      }
      break;
    }
    default:
      break;
  }
  if (!address_range_allowed(function, address, count)) {
    return refuse(MODBUS_EXCEPTION_ILLEGAL_DATA_ADDRESS,
                  "function " + std::to_string(function) + " at address " +
                      std::to_string(address) + " count " + std::to_string(count) +
                      " is outside the register map or read-only");
  }
  return check_page_select(pdu, function, address, count);
}

}  // namespace

FrameHeader check_mbap_prefix(const std::uint8_t* bytes, std::size_t size) {
  FrameHeader header;
  if (size < kMbapLengthPrefix) {
    header.problem = "short MBAP header";
    return header;
  }
  const std::uint32_t protocol = word(bytes + 2);
  const std::uint32_t length = word(bytes + 4);
  if (protocol != 0) {
    header.problem = "protocol id " + std::to_string(protocol) + " (Modbus is 0)";
    return header;
  }
  if (length < 2 || length > kMaxMbapLength) {
    header.problem = "MBAP length " + std::to_string(length) + " outside 2..254";
    return header;
  }
  header.valid = true;
  header.frame_bytes = kMbapLengthPrefix + length;
  return header;
}

RequestVerdict check_request(const std::uint8_t* adu, std::size_t size,
                             const RequestCheckSettings& settings) {
  const FrameHeader header = check_mbap_prefix(adu, size);
  if (!header.valid || header.frame_bytes != size) {
    return refuse(MODBUS_EXCEPTION_ILLEGAL_DATA_VALUE, "frame length does not match MBAP");
  }
  const int function = adu[kMbapHeaderBytes];
  switch (function) {
    case MODBUS_FC_READ_COILS:
    case MODBUS_FC_READ_DISCRETE_INPUTS:
    case MODBUS_FC_READ_HOLDING_REGISTERS:
    case MODBUS_FC_READ_INPUT_REGISTERS:
    case MODBUS_FC_WRITE_SINGLE_COIL:
    case MODBUS_FC_WRITE_SINGLE_REGISTER:
    case MODBUS_FC_WRITE_MULTIPLE_COILS:
    case MODBUS_FC_WRITE_MULTIPLE_REGISTERS:
      break;
    default:
      // Least functionality (IEC 62443 CR 7.7): FC23, diagnostics, report id and the rest.
      return refuse(MODBUS_EXCEPTION_ILLEGAL_FUNCTION,
                    "function code " + std::to_string(function) + " is not served");
  }
  const std::uint8_t unit = adu[kMbapHeaderBytes - 1];
  // 0xFF and 0 both address the device itself on Modbus TCP (the Messaging on TCP/IP
  // Implementation Guide recommends 0xFF and accepts 0); pymodbus sends 0 by default.
  if (unit != settings.unit_id && unit != 0xFF && unit != 0) {
    return refuse(MODBUS_EXCEPTION_GATEWAY_TARGET, "unit id " + std::to_string(unit) +
                                                       " (this station is unit " +
                                                       std::to_string(settings.unit_id) + ")");
  }
  return check_pdu(adu + kMbapHeaderBytes, size - kMbapHeaderBytes);
}

bool address_range_allowed(int function, std::uint32_t first, std::uint32_t count) {
  switch (function) {
    case MODBUS_FC_READ_COILS:
    case MODBUS_FC_WRITE_SINGLE_COIL:
    case MODBUS_FC_WRITE_MULTIPLE_COILS:
      return inside(kCoils, first, count);
    case MODBUS_FC_READ_DISCRETE_INPUTS:
      return inside(kDiscreteInputs, first, count);
    case MODBUS_FC_READ_HOLDING_REGISTERS:
      return inside(kReadableHolding, first, count);
    case MODBUS_FC_WRITE_SINGLE_REGISTER:
    case MODBUS_FC_WRITE_MULTIPLE_REGISTERS:
      return inside(kWritableHolding, first, count);
    case MODBUS_FC_READ_INPUT_REGISTERS:
      return inside(kInputRegisters, first, count);
    default:
      return false;
  }
}

}  // namespace springscan::daemon
