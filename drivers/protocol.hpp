#pragma once
// Wire constants of the springscan scanner protocol, version 1. The one header that both the
// host drivers and the scanner simulator include (STYLE.md §6, §7). Every constant cites its
// section of docs/device-protocol.md. All multi-byte fields are little-endian (§2).

#include <cstddef>
#include <cstdint>

namespace springscan::drivers::protocol {

// §1 USB identity and endpoints.
inline constexpr std::uint16_t kVendorId = 0x1209;          ///< §1: pid.codes vendor id
inline constexpr std::uint16_t kProductIdLaser = 0x5301;    ///< §1: laser line scanner
inline constexpr std::uint16_t kProductIdTactile = 0x5302;  ///< §1: tactile probe
inline constexpr int kInterfaceNumber = 0;                  ///< §1: the vendor interface
inline constexpr std::uint8_t kEndpointOut = 0x02;          ///< §1: bulk OUT, commands
inline constexpr std::uint8_t kEndpointIn = 0x81;           ///< §1: bulk IN, replies and data
inline constexpr std::uint16_t kMaxPacketSize = 512;        ///< §1: high-speed bulk packets
inline constexpr std::uint8_t kStringManufacturer = 1;      ///< §1: string descriptor index
inline constexpr std::uint8_t kStringProduct = 2;           ///< §1: string descriptor index
inline constexpr std::uint8_t kStringSerial = 3;            ///< §1: string descriptor index

// §2 Frame layout: header | payload | CRC-32.
inline constexpr std::uint8_t kMagic[4] = {'S', 'S', 'C', 'N'};  ///< §2.1: frame start
inline constexpr std::uint8_t kProtocolVersion = 1;              ///< §2.1
inline constexpr std::size_t kHeaderBytes = 16;                  ///< §2.1
inline constexpr std::size_t kCrcBytes = 4;                      ///< §2.2
inline constexpr std::size_t kMaxPayloadBytes = 65536 - kHeaderBytes - kCrcBytes;  ///< §2.3
inline constexpr std::size_t kMaxFrameBytes = kHeaderBytes + kMaxPayloadBytes + kCrcBytes;
// Header field offsets (§2.1).
inline constexpr std::size_t kOffsetVersion = 4;
inline constexpr std::size_t kOffsetType = 5;
inline constexpr std::size_t kOffsetFlags = 6;
inline constexpr std::size_t kOffsetSequence = 8;
inline constexpr std::size_t kOffsetLength = 12;

/// §3: message types. Commands go host to device (bulk OUT); the rest come back on bulk IN.
enum class MessageType : std::uint8_t {
  kIdentify = 0x01,      ///< §3.1
  kGetConfig = 0x02,     ///< §3.2
  kSetConfig = 0x03,     ///< §3.2
  kStartScan = 0x04,     ///< §3.3
  kStopScan = 0x05,      ///< §3.3
  kGetStatus = 0x06,     ///< §3.4
  kIdentity = 0x81,      ///< §3.1 reply
  kConfig = 0x82,        ///< §3.2 reply (to get and set)
  kScanStarted = 0x84,   ///< §3.3 reply
  kScanStopped = 0x85,   ///< §3.3 reply
  kStatus = 0x86,        ///< §3.4 reply
  kLaserProfile = 0x90,  ///< §4.1 data
  kProbePoints = 0x91,   ///< §4.2 data
  kEndOfScan = 0x9F,     ///< §4.3
  kError = 0xE0,         ///< §5
};

/// §3.1: what kind of scanner answers.
enum class ScannerKind : std::uint8_t { kLaserLine = 1, kTactileProbe = 2 };

/// §3.4: device state in a status reply.
enum class DeviceState : std::uint8_t { kIdle = 0, kScanning = 1, kFault = 2 };

/// §5: error codes in an error frame.
enum class DeviceErrorCode : std::uint16_t {
  kUnknownCommand = 1,  ///< §5: type not a command
  kBadPayload = 2,      ///< §5: payload size or value invalid
  kBusy = 3,            ///< §5: a scan is running
  kNotScanning = 4,     ///< §5: stop without a scan
  kSensorFault = 5,     ///< §5: the sensor failed mid-scan
  kOverrun = 6,         ///< §5: host too slow, device buffer overflowed
  kBadFrame = 7,        ///< §5: a command frame failed its CRC
};

// §3.1 identity payload: kind u8, 3 reserved, then three NUL-padded ASCII fields.
inline constexpr std::size_t kModelBytes = 32;
inline constexpr std::size_t kSerialBytes = 32;
inline constexpr std::size_t kFirmwareBytes = 16;
inline constexpr std::size_t kIdentityPayloadBytes =
    4 + kModelBytes + kSerialBytes + kFirmwareBytes;

// §3.2 configuration payload.
inline constexpr std::size_t kConfigPayloadBytes = 16;

// §3.3 scan-started payload: expected data frames u32, expected points u32, scan id u32.
inline constexpr std::size_t kScanStartedPayloadBytes = 12;

// §3.4 status payload.
inline constexpr std::size_t kStatusPayloadBytes = 16;

// §4.1 laser profile: index u32, count u16, reserved u16, encoder f64 (mm), timestamp u64 (us),
// then count x (x f32, z f32) in mm, sensor frame; NaN z marks no return.
inline constexpr std::size_t kProfileHeaderBytes = 24;
inline constexpr std::size_t kProfilePointBytes = 8;
inline constexpr std::size_t kMaxProfilePoints = 4096;

// §4.2 probe points: first index u32, count u16, reserved u16, timestamp u64 (us), then count x
// (x, y, z f64 stylus centre, mm; direction 3 x f32 unit; stylus radius f32 mm).
inline constexpr std::size_t kProbeHeaderBytes = 16;
inline constexpr std::size_t kProbeRecordBytes = 40;
inline constexpr std::size_t kMaxProbeRecords = 1024;

// §4.3 end of scan: data frames u32, dropped frames u32, points u64, duration u64 (us).
inline constexpr std::size_t kEndOfScanPayloadBytes = 24;

// §5 error: code u16, reserved u16, offending command sequence u32, message (ASCII, no NUL).
inline constexpr std::size_t kErrorHeaderBytes = 8;
inline constexpr std::size_t kMaxErrorMessageBytes = 200;

// §6 limits of one scan.
inline constexpr std::uint32_t kMaxScanFrames = 1'000'000;   ///< §6
inline constexpr std::uint64_t kMaxScanPoints = 50'000'000;  ///< §6

static_assert(kProfileHeaderBytes + kMaxProfilePoints * kProfilePointBytes <= kMaxPayloadBytes);
static_assert(kProbeHeaderBytes + kMaxProbeRecords * kProbeRecordBytes <= kMaxPayloadBytes);

}  // namespace springscan::drivers::protocol
