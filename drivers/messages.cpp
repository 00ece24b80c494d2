#include "drivers/messages.hpp"

#include <algorithm>
#include <cstring>

#include "drivers/wire.hpp"

namespace springscan::drivers {
namespace {

namespace p = protocol;

// Every decode failure here means the device sent a payload the protocol does not allow.
analysis::Error fail(std::string message) {
  return analysis::fail(analysis::ErrorCode::kProtocolError, std::move(message));
}

void put_text(std::uint8_t* out, std::size_t field_bytes, const std::string& text) {
  // NUL-padded, always NUL-terminated (§3.1).
  const std::size_t n = std::min(text.size(), field_bytes - 1);
  std::memcpy(out, text.data(), n);
  std::memset(out + n, 0, field_bytes - n);
}

std::string get_text(const std::uint8_t* in, std::size_t field_bytes) {
  std::size_t n = 0;
  while (n < field_bytes && in[n] != 0) ++n;
  return std::string(reinterpret_cast<const char*>(in), n);
}

analysis::Error size_error(const char* what, std::size_t expected, std::size_t seen) {
  return fail(std::string(what) + " payload: expected " + std::to_string(expected) +
              " bytes, got " + std::to_string(seen));
}

}  // namespace

Bytes encode(const Identity& identity) {
  Bytes out(p::kIdentityPayloadBytes, 0);
  out[0] = static_cast<std::uint8_t>(identity.kind);
  put_text(out.data() + 4, p::kModelBytes, identity.model);
  put_text(out.data() + 4 + p::kModelBytes, p::kSerialBytes, identity.serial);
  put_text(out.data() + 4 + p::kModelBytes + p::kSerialBytes, p::kFirmwareBytes, identity.firmware);
  return out;
}

analysis::Expected<Identity> decode_identity(ByteSpan payload) {
  if (payload.size() != p::kIdentityPayloadBytes)
    return size_error("identity", p::kIdentityPayloadBytes, payload.size());
  Identity id;
  const std::uint8_t kind = payload[0];
  if (kind != 1 && kind != 2)
    return fail("identity payload: unknown scanner kind " + std::to_string(kind));
  id.kind = static_cast<p::ScannerKind>(kind);
  id.model = get_text(payload.data() + 4, p::kModelBytes);
  id.serial = get_text(payload.data() + 4 + p::kModelBytes, p::kSerialBytes);
  id.firmware = get_text(payload.data() + 4 + p::kModelBytes + p::kSerialBytes, p::kFirmwareBytes);
  return id;
}

Bytes encode(const DeviceConfig& c) {
  Bytes out(p::kConfigPayloadBytes, 0);
  wire::store_f32(out.data(), c.rate_hz);
  wire::store_u16(out.data() + 4, c.points_per_profile);
  wire::store_u16(out.data() + 6, c.flags);
  wire::store_u32(out.data() + 8, c.exposure_us);
  wire::store_f32(out.data() + 12, c.probe_speed_mm_s);
  return out;
}

analysis::Expected<DeviceConfig> decode_config(ByteSpan payload) {
  if (payload.size() != p::kConfigPayloadBytes)
    return size_error("config", p::kConfigPayloadBytes, payload.size());
  DeviceConfig c;
  c.rate_hz = wire::load_f32(payload.data());
  c.points_per_profile = wire::load_u16(payload.data() + 4);
  c.flags = wire::load_u16(payload.data() + 6);
  c.exposure_us = wire::load_u32(payload.data() + 8);
  c.probe_speed_mm_s = wire::load_f32(payload.data() + 12);
  // §3.2 value ranges.
  if (!(c.rate_hz > 0.0f && c.rate_hz <= 100000.0f))
    return fail("config payload: rate_hz " + std::to_string(c.rate_hz) + " outside (0, 1e5]");
  if (c.points_per_profile == 0 || c.points_per_profile > p::kMaxProfilePoints)
    return fail("config payload: points_per_profile " + std::to_string(c.points_per_profile) +
                " outside [1, 4096]");
  if (!(c.probe_speed_mm_s > 0.0f))
    return fail("config payload: probe_speed_mm_s " + std::to_string(c.probe_speed_mm_s) +
                " must be positive");
  return c;
}

Bytes encode(const ScanStarted& s) {
  Bytes out(p::kScanStartedPayloadBytes, 0);
  wire::store_u32(out.data(), s.expected_frames);
  wire::store_u32(out.data() + 4, s.expected_points);
  wire::store_u32(out.data() + 8, s.scan_id);
  return out;
}

analysis::Expected<ScanStarted> decode_scan_started(ByteSpan payload) {
  if (payload.size() != p::kScanStartedPayloadBytes)
    return size_error("scan-started", p::kScanStartedPayloadBytes, payload.size());
  ScanStarted s{wire::load_u32(payload.data()), wire::load_u32(payload.data() + 4),
                wire::load_u32(payload.data() + 8)};
  if (s.expected_frames > p::kMaxScanFrames || s.expected_points > p::kMaxScanPoints)
    return fail("scan-started payload: " + std::to_string(s.expected_frames) + " frames / " +
                std::to_string(s.expected_points) + " points exceed the limits of §6");
  return s;
}

Bytes encode(const DeviceStatus& s) {
  Bytes out(p::kStatusPayloadBytes, 0);
  out[0] = static_cast<std::uint8_t>(s.state);
  wire::store_u16(out.data() + 2, s.last_error);
  wire::store_u32(out.data() + 4, s.frames_sent);
  wire::store_u32(out.data() + 8, s.frames_expected);
  wire::store_u32(out.data() + 12, s.scan_id);
  return out;
}

analysis::Expected<DeviceStatus> decode_status(ByteSpan payload) {
  if (payload.size() != p::kStatusPayloadBytes)
    return size_error("status", p::kStatusPayloadBytes, payload.size());
  if (payload[0] > 2) return fail("status payload: unknown state " + std::to_string(payload[0]));
  return DeviceStatus{static_cast<p::DeviceState>(payload[0]), wire::load_u16(payload.data() + 2),
                      wire::load_u32(payload.data() + 4), wire::load_u32(payload.data() + 8),
                      wire::load_u32(payload.data() + 12)};
}

Bytes encode(const EndOfScan& s) {
  Bytes out(p::kEndOfScanPayloadBytes, 0);
  wire::store_u32(out.data(), s.data_frames);
  wire::store_u32(out.data() + 4, s.dropped_frames);
  wire::store_u64(out.data() + 8, s.points);
  wire::store_u64(out.data() + 16, s.duration_us);
  return out;
}

analysis::Expected<EndOfScan> decode_end_of_scan(ByteSpan payload) {
  if (payload.size() != p::kEndOfScanPayloadBytes)
    return size_error("end-of-scan", p::kEndOfScanPayloadBytes, payload.size());
  return EndOfScan{wire::load_u32(payload.data()), wire::load_u32(payload.data() + 4),
                   wire::load_u64(payload.data() + 8), wire::load_u64(payload.data() + 16)};
}

Bytes encode(const DeviceError& e) {
  const std::size_t n = std::min(e.message.size(), p::kMaxErrorMessageBytes);
  Bytes out(p::kErrorHeaderBytes + n, 0);
  wire::store_u16(out.data(), e.code);
  wire::store_u32(out.data() + 4, e.command_sequence);
  std::memcpy(out.data() + p::kErrorHeaderBytes, e.message.data(), n);
  return out;
}

analysis::Expected<DeviceError> decode_error(ByteSpan payload) {
  if (payload.size() < p::kErrorHeaderBytes ||
      payload.size() > p::kErrorHeaderBytes + p::kMaxErrorMessageBytes)
    return fail("error payload: " + std::to_string(payload.size()) + " bytes, expected 8..208");
  DeviceError e;
  e.code = wire::load_u16(payload.data());
  e.command_sequence = wire::load_u32(payload.data() + 4);
  e.message.assign(reinterpret_cast<const char*>(payload.data() + p::kErrorHeaderBytes),
                   payload.size() - p::kErrorHeaderBytes);
  return e;
}

Bytes encode_laser_profile(std::uint32_t index, double encoder_mm, std::uint64_t timestamp_us,
                           std::span<const SensorPoint> points) {
  const std::size_t n = std::min(points.size(), p::kMaxProfilePoints);
  Bytes out(p::kProfileHeaderBytes + n * p::kProfilePointBytes, 0);
  wire::store_u32(out.data(), index);
  wire::store_u16(out.data() + 4, static_cast<std::uint16_t>(n));
  wire::store_f64(out.data() + 8, encoder_mm);
  wire::store_u64(out.data() + 16, timestamp_us);
  std::uint8_t* q = out.data() + p::kProfileHeaderBytes;
  for (std::size_t i = 0; i < n; ++i, q += p::kProfilePointBytes) {
    wire::store_f32(q, points[i].x_mm);
    wire::store_f32(q + 4, points[i].z_mm);
  }
  return out;
}

analysis::Expected<LaserProfileView> decode_laser_profile(ByteSpan payload) {
  if (payload.size() < p::kProfileHeaderBytes)
    return fail("laser profile payload: " + std::to_string(payload.size()) +
                " bytes, shorter than its 24-byte header");
  LaserProfileView v;
  v.index = wire::load_u32(payload.data());
  v.count = wire::load_u16(payload.data() + 4);
  v.encoder_mm = wire::load_f64(payload.data() + 8);
  v.timestamp_us = wire::load_u64(payload.data() + 16);
  const std::size_t expected = p::kProfileHeaderBytes + v.count * p::kProfilePointBytes;
  if (v.count > p::kMaxProfilePoints || payload.size() != expected)
    return fail("laser profile " + std::to_string(v.index) + ": " + std::to_string(v.count) +
                " points need " + std::to_string(expected) + " bytes, payload has " +
                std::to_string(payload.size()));
  v.points = payload.subspan(p::kProfileHeaderBytes);
  return v;
}

Bytes encode_probe_batch(std::uint32_t first_index, std::uint64_t timestamp_us,
                         std::span<const ProbeRecord> records) {
  const std::size_t n = std::min(records.size(), p::kMaxProbeRecords);
  Bytes out(p::kProbeHeaderBytes + n * p::kProbeRecordBytes, 0);
  wire::store_u32(out.data(), first_index);
  wire::store_u16(out.data() + 4, static_cast<std::uint16_t>(n));
  wire::store_u64(out.data() + 8, timestamp_us);
  std::uint8_t* q = out.data() + p::kProbeHeaderBytes;
  for (std::size_t i = 0; i < n; ++i, q += p::kProbeRecordBytes) {
    for (int k = 0; k < 3; ++k) wire::store_f64(q + 8 * k, records[i].center_mm[k]);
    for (int k = 0; k < 3; ++k) wire::store_f32(q + 24 + 4 * k, records[i].direction[k]);
    wire::store_f32(q + 36, records[i].stylus_radius_mm);
  }
  return out;
}

analysis::Expected<ProbeBatchView> decode_probe_batch(ByteSpan payload) {
  if (payload.size() < p::kProbeHeaderBytes)
    return fail("probe batch payload: " + std::to_string(payload.size()) +
                " bytes, shorter than its 16-byte header");
  ProbeBatchView v;
  v.first_index = wire::load_u32(payload.data());
  v.count = wire::load_u16(payload.data() + 4);
  v.timestamp_us = wire::load_u64(payload.data() + 8);
  const std::size_t expected = p::kProbeHeaderBytes + v.count * p::kProbeRecordBytes;
  if (v.count > p::kMaxProbeRecords || payload.size() != expected)
    return fail("probe batch " + std::to_string(v.first_index) + ": " + std::to_string(v.count) +
                " records need " + std::to_string(expected) + " bytes, payload has " +
                std::to_string(payload.size()));
  v.records = payload.subspan(p::kProbeHeaderBytes);
  return v;
}

ProbeRecord probe_record(const ProbeBatchView& batch, std::size_t i) {
  const std::uint8_t* q = batch.records.data() + i * p::kProbeRecordBytes;
  ProbeRecord r;
  for (int k = 0; k < 3; ++k) r.center_mm[k] = wire::load_f64(q + 8 * k);
  for (int k = 0; k < 3; ++k) r.direction[k] = wire::load_f32(q + 24 + 4 * k);
  r.stylus_radius_mm = wire::load_f32(q + 36);
  return r;
}

std::string to_string(p::MessageType type) {
  switch (type) {
    case p::MessageType::kIdentify:
      return "identify";
    case p::MessageType::kGetConfig:
      return "get-config";
    case p::MessageType::kSetConfig:
      return "set-config";
    case p::MessageType::kStartScan:
      return "start-scan";
    case p::MessageType::kStopScan:
      return "stop-scan";
    case p::MessageType::kGetStatus:
      return "get-status";
    case p::MessageType::kIdentity:
      return "identity";
    case p::MessageType::kConfig:
      return "config";
    case p::MessageType::kScanStarted:
      return "scan-started";
    case p::MessageType::kScanStopped:
      return "scan-stopped";
    case p::MessageType::kStatus:
      return "status";
    case p::MessageType::kLaserProfile:
      return "laser-profile";
    case p::MessageType::kProbePoints:
      return "probe-points";
    case p::MessageType::kEndOfScan:
      return "end-of-scan";
    case p::MessageType::kError:
      return "error";
  }
  return "type 0x" + std::to_string(static_cast<int>(type));
}

std::string to_string(p::DeviceErrorCode code) {
  switch (code) {
    case p::DeviceErrorCode::kUnknownCommand:
      return "unknown command";
    case p::DeviceErrorCode::kBadPayload:
      return "bad payload";
    case p::DeviceErrorCode::kBusy:
      return "busy (scan running)";
    case p::DeviceErrorCode::kNotScanning:
      return "not scanning";
    case p::DeviceErrorCode::kSensorFault:
      return "sensor fault";
    case p::DeviceErrorCode::kOverrun:
      return "overrun";
    case p::DeviceErrorCode::kBadFrame:
      return "bad command frame";
  }
  return "device error " + std::to_string(static_cast<int>(code));
}

std::string to_string(p::ScannerKind kind) {
  return kind == p::ScannerKind::kLaserLine ? "laser_line" : "tactile_probe";
}

}  // namespace springscan::drivers
