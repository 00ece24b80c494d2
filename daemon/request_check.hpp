#pragma once
// Validation of a Modbus TCP request before libmodbus sees it (notes section 2,
// "Pre-validation before modbus_reply"). Debian's libmodbus 3.1.6 has weak request checks
// (FC23 heap overflow #614, no request-length check before 3.1.11, short-frame reads #837), so
// only requests that pass here reach modbus_receive/modbus_reply. Pure functions over bytes.
//
// Wire format: Modbus Messaging on TCP/IP Implementation Guide V1.0b, section 3.1.3 (MBAP:
// transaction id 2, protocol id 2 = 0, length 2 = unit id + PDU bytes, unit id 1), and
// Modbus Application Protocol V1.1b3, section 6 (PDU of each function code).

#include <cstddef>
#include <cstdint>
#include <string>

namespace springscan::daemon {

inline constexpr std::size_t kMbapHeaderBytes = 7;   ///< incl. the unit id
inline constexpr std::size_t kMbapLengthPrefix = 6;  ///< bytes before the counted part
inline constexpr std::size_t kMaxMbapLength = 254;   ///< unit id + 253-byte PDU
inline constexpr std::size_t kMaxAduBytes = kMbapLengthPrefix + kMaxMbapLength;

/// The outcome of the framing check on the first 6 bytes.
struct FrameHeader {
  bool valid = false;           ///< false: not Modbus TCP; close the connection
  std::size_t frame_bytes = 0;  ///< total ADU length to wait for
  std::string problem;          ///< why it is invalid, for the log
};

/// Reads the MBAP prefix (needs >= 6 bytes): protocol id must be 0, length 2..254.
FrameHeader check_mbap_prefix(const std::uint8_t* bytes, std::size_t size);

/// What to do with a complete, well-framed request.
struct RequestVerdict {
  int exception = 0;    ///< 0: pass to modbus_reply; else the Modbus exception code to answer
  std::string problem;  ///< why it was refused, for the log
};

struct RequestCheckSettings {
  std::uint8_t unit_id = 1;  ///< also accepted: 0xFF and 0, the "this device" values of TCP
};

/// Checks a complete ADU (MBAP + PDU, as framed by check_mbap_prefix): function-code
/// whitelist (1,2,3,4,5,6,15,16 -> else 01), PDU length and quantities (-> 03), address
/// ranges and writes to read-only areas (-> 02), PAGE_SELECT values past the last page (-> 03),
/// unit id (-> 0B, gateway target failed).
RequestVerdict check_request(const std::uint8_t* adu, std::size_t size,
                             const RequestCheckSettings& settings = {});

/// True when [first, first + count) lies inside one readable block of the table that
/// `function` reads or writes (register map). Exposed for tests and the PLC simulator.
bool address_range_allowed(int function, std::uint32_t first, std::uint32_t count);

}  // namespace springscan::daemon
