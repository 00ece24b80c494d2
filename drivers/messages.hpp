#pragma once
// Payloads of the scanner protocol (docs/device-protocol.md §3-§5): plain structs and their
// encoders and decoders. Pure and shared by the drivers and the simulator. Decoders check
// sizes against the payload they are given and never allocate by a length read off the wire.

#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "analysis/core/expected.hpp"
#include "drivers/protocol.hpp"

namespace springscan::drivers {

using Bytes = std::vector<std::uint8_t>;
using ByteSpan = std::span<const std::uint8_t>;

/// §3.1 the identify reply.
struct Identity {
  protocol::ScannerKind kind = protocol::ScannerKind::kLaserLine;
  std::string model;     ///< at most 31 ASCII characters on the wire
  std::string serial;    ///< at most 31
  std::string firmware;  ///< at most 15
};

/// §3.2 the device configuration (get and set).
struct DeviceConfig {
  float rate_hz = 200.0f;  ///< profiles (laser) or probe points (tactile) per second
  std::uint16_t points_per_profile = 1024;  ///< laser: points across the line, 1..4096
  std::uint16_t flags = 0;                  ///< reserved, 0
  std::uint32_t exposure_us = 100;          ///< laser exposure time
  float probe_speed_mm_s = 10.0f;           ///< tactile approach speed
};

/// §3.3 the reply to start-scan: what the host should expect.
struct ScanStarted {
  std::uint32_t expected_frames = 0;  ///< data frames the scan will send
  std::uint32_t expected_points = 0;  ///< points in those frames (upper bound)
  std::uint32_t scan_id = 0;          ///< increments per scan
};

/// §3.4 the status reply.
struct DeviceStatus {
  protocol::DeviceState state = protocol::DeviceState::kIdle;
  std::uint16_t last_error = 0;  ///< a DeviceErrorCode or 0
  std::uint32_t frames_sent = 0;
  std::uint32_t frames_expected = 0;
  std::uint32_t scan_id = 0;
};

/// §4.3 the end-of-scan summary.
struct EndOfScan {
  std::uint32_t data_frames = 0;     ///< data frames the device sent in this scan
  std::uint32_t dropped_frames = 0;  ///< frames the device had to drop (buffer overrun)
  std::uint64_t points = 0;          ///< points in the data frames
  std::uint64_t duration_us = 0;     ///< start to end of the scan
};

/// §5 an error frame.
struct DeviceError {
  std::uint16_t code = 0;              ///< a protocol::DeviceErrorCode
  std::uint32_t command_sequence = 0;  ///< the command it answers, 0 when spontaneous
  std::string message;                 ///< at most 200 ASCII characters
};

/// §4.1 the fixed part of a laser profile; `points` are count x (x f32, z f32), sensor frame mm.
struct LaserProfileView {
  std::uint32_t index = 0;
  std::uint16_t count = 0;
  double encoder_mm = 0.0;
  std::uint64_t timestamp_us = 0;
  ByteSpan points;
};

/// A laser point in the sensor's profile plane (mm). NaN z: no return.
struct SensorPoint {
  float x_mm = 0.0f;
  float z_mm = 0.0f;
};

/// §4.2 one tactile probe record: stylus centre (machine frame), approach direction, radius.
struct ProbeRecord {
  std::array<double, 3> center_mm{};
  std::array<float, 3> direction{};  ///< unit vector, the direction the stylus moved to touch
  float stylus_radius_mm = 0.0f;
};

/// §4.2 the fixed part of a probe batch; `records` are count x 40 bytes.
struct ProbeBatchView {
  std::uint32_t first_index = 0;
  std::uint16_t count = 0;
  std::uint64_t timestamp_us = 0;
  ByteSpan records;
};

Bytes encode(const Identity& identity);
Bytes encode(const DeviceConfig& config);
Bytes encode(const ScanStarted& started);
Bytes encode(const DeviceStatus& status);
Bytes encode(const EndOfScan& summary);
Bytes encode(const DeviceError& error);
Bytes encode_laser_profile(std::uint32_t index, double encoder_mm, std::uint64_t timestamp_us,
                           std::span<const SensorPoint> points);
Bytes encode_probe_batch(std::uint32_t first_index, std::uint64_t timestamp_us,
                         std::span<const ProbeRecord> records);

analysis::Expected<Identity> decode_identity(ByteSpan payload);
analysis::Expected<DeviceConfig> decode_config(ByteSpan payload);
analysis::Expected<ScanStarted> decode_scan_started(ByteSpan payload);
analysis::Expected<DeviceStatus> decode_status(ByteSpan payload);
analysis::Expected<EndOfScan> decode_end_of_scan(ByteSpan payload);
analysis::Expected<DeviceError> decode_error(ByteSpan payload);
analysis::Expected<LaserProfileView> decode_laser_profile(ByteSpan payload);
analysis::Expected<ProbeBatchView> decode_probe_batch(ByteSpan payload);

/// Reads record i of a decoded batch (i < count).
ProbeRecord probe_record(const ProbeBatchView& batch, std::size_t i);

std::string to_string(protocol::MessageType type);
std::string to_string(protocol::DeviceErrorCode code);
std::string to_string(protocol::ScannerKind kind);

}  // namespace springscan::drivers
