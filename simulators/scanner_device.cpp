#include "simulators/scanner_device.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <numbers>

namespace springscan::simulators {
namespace {

namespace p = drivers::protocol;
using Clock = std::chrono::steady_clock;

// The device's bulk IN FIFO: beyond this it stops measuring ahead of the host.
constexpr std::size_t kFifoBytes = 256 * 1024;

}  // namespace

analysis::PointCloud replaced(const analysis::PointCloud& surface,
                              const ScannerDeviceSettings& settings, std::mt19937& rng) {
  if (!(settings.replace_mm > 0.0) && !(settings.replace_deg > 0.0)) return surface;
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  analysis::Vec3 axis;
  do {
    axis = analysis::Vec3(unit(rng), unit(rng), unit(rng));
  } while (axis.norm() < 0.1 || axis.norm() > 1.0);  // uniform direction: inside the ball
  const double angle = unit(rng) * settings.replace_deg * std::numbers::pi / 180.0;
  const analysis::Vec3 shift =
      settings.replace_mm * analysis::Vec3(unit(rng), unit(rng), unit(rng));
  analysis::Vec3 centroid = analysis::Vec3::Zero();
  for (const auto& p : surface.points) centroid += p;
  if (!surface.points.empty()) centroid /= static_cast<double>(surface.points.size());
  const Eigen::Matrix3d R = Eigen::AngleAxisd(angle, axis.normalized()).toRotationMatrix();
  analysis::PointCloud moved = surface;
  for (auto& p : moved.points) p = R * (p - centroid) + centroid + shift;
  for (auto& n : moved.normals) n = R * n;
  return moved;
}

ScannerDevice::ScannerDevice(const ScannerDeviceSettings& settings, analysis::PointCloud surface)
    : settings_(settings), surface_(std::move(surface)), rng_(settings.seed) {}

void ScannerDevice::receive(std::span<const std::uint8_t> bytes) {
  decoder_.feed(bytes);
  drivers::FrameView frame;
  for (;;) {
    const auto status = decoder_.next(frame);
    if (status == drivers::DecodeStatus::kNeedMore) break;
    if (status == drivers::DecodeStatus::kFrame) {
      handle(frame);
    } else {
      emit_error(p::DeviceErrorCode::kBadFrame, 0,
                 "command frame rejected: " + drivers::to_string(status));
    }
  }
}

void ScannerDevice::handle(const drivers::FrameView& frame) {
  const std::uint32_t seq = frame.header.sequence;
  const bool busy = scanning_;
  switch (frame.header.type) {
    case p::MessageType::kIdentify:
      if (busy) break;
      emit(p::MessageType::kIdentity, drivers::encode(settings_.identity));
      return;
    case p::MessageType::kGetConfig:
      if (busy) break;
      emit(p::MessageType::kConfig, drivers::encode(settings_.config));
      return;
    case p::MessageType::kSetConfig: {
      if (busy) break;
      auto config = drivers::decode_config(frame.payload);
      if (!config) return emit_error(p::DeviceErrorCode::kBadPayload, seq, config.message());
      settings_.config = *config;
      settings_.laser.points_per_profile = config->points_per_profile;
      emit(p::MessageType::kConfig, drivers::encode(settings_.config));
      return;
    }
    case p::MessageType::kStartScan:
      if (busy) break;
      return start_scan(seq);
    case p::MessageType::kStopScan:
      if (!scanning_) return emit_error(p::DeviceErrorCode::kNotScanning, seq, "no scan running");
      return stop_scan();
    case p::MessageType::kGetStatus: {
      const drivers::DeviceStatus status{
          scanning_ ? p::DeviceState::kScanning : p::DeviceState::kIdle, 0, next_frame_,
          frames_total(), scan_id_};
      emit(p::MessageType::kStatus, drivers::encode(status));
      return;
    }
    default:
      return emit_error(p::DeviceErrorCode::kUnknownCommand, seq,
                        "unknown command " + drivers::to_string(frame.header.type));
  }
  emit_error(p::DeviceErrorCode::kBusy, seq, "a scan is running");
}

void ScannerDevice::start_scan(std::uint32_t command_sequence) {
  frames_.clear();
  scan_points_ = 0;
  const double duration_us = settings_.scan_duration_s * 1e6;
  if (settings_.identity.kind == p::ScannerKind::kLaserLine) {
    const auto profiles =
        laser_profiles(replaced(surface_, settings_, rng_), settings_.laser, settings_.noise, rng_);
    for (std::size_t k = 0; k < profiles.size(); ++k) {
      const auto t = static_cast<std::uint64_t>(duration_us * double(k) / double(profiles.size()));
      frames_.push_back(drivers::encode_laser_profile(
          static_cast<std::uint32_t>(k), profiles[k].encoder_mm, t, profiles[k].points));
      scan_points_ += profiles[k].points.size();
    }
  } else {
    const auto records =
        probe_grid(replaced(surface_, settings_, rng_), settings_.probe, settings_.noise, rng_);
    const auto per =
        static_cast<std::size_t>(std::clamp(settings_.probe.records_per_frame, 1, 1024));
    for (std::size_t first = 0; first < records.size(); first += per) {
      const std::size_t n = std::min(per, records.size() - first);
      const auto t =
          static_cast<std::uint64_t>(duration_us * double(first) / double(records.size()));
      frames_.push_back(drivers::encode_probe_batch(static_cast<std::uint32_t>(first), t,
                                                    std::span(records).subspan(first, n)));
    }
    scan_points_ = records.size();
  }
  if (frames_.size() > p::kMaxScanFrames || scan_points_ > p::kMaxScanPoints) {
    frames_.clear();
    return emit_error(p::DeviceErrorCode::kBadPayload, command_sequence,
                      "the part needs more frames or points than one scan may hold (§6)");
  }
  ++scan_id_;
  next_frame_ = 0;
  scanning_ = true;
  stalled_ = false;
  scan_start_ = Clock::now();
  emit(p::MessageType::kScanStarted,
       drivers::encode(drivers::ScanStarted{frames_total(),
                                            static_cast<std::uint32_t>(scan_points_), scan_id_}));
}

void ScannerDevice::stop_scan() {
  const drivers::EndOfScan summary{next_frame_, 0, scan_points_, 0};
  emit(p::MessageType::kEndOfScan, drivers::encode(summary));
  emit(p::MessageType::kScanStopped, {});
  scanning_ = false;
  stalled_ = false;
}

void ScannerDevice::emit(p::MessageType type, std::span<const std::uint8_t> payload) {
  drivers::append_frame(out_, type, sequence_++, payload);
}

void ScannerDevice::emit_error(p::DeviceErrorCode code, std::uint32_t command_sequence,
                               const std::string& message) {
  emit(p::MessageType::kError, drivers::encode(drivers::DeviceError{
                                   static_cast<std::uint16_t>(code), command_sequence, message}));
}

bool ScannerDevice::fault_due(double& fraction) {
  if (fraction < 0.0) return false;
  const auto at = static_cast<std::uint32_t>(std::floor(fraction * double(frames_.size())));
  if (next_frame_ < at) return false;
  fraction = -1.0;  // fires once
  return true;
}

void ScannerDevice::produce_due_frames() {
  auto& f = settings_.faults;
  const auto type = settings_.identity.kind == p::ScannerKind::kLaserLine
                        ? p::MessageType::kLaserProfile
                        : p::MessageType::kProbePoints;
  const double elapsed_s = std::chrono::duration<double>(Clock::now() - scan_start_).count();
  while (scanning_ && !stalled_ && event_ == DeviceEvent::kNone &&
         out_.size() - out_read_ < kFifoBytes) {
    if (next_frame_ == frames_.size()) {
      const drivers::EndOfScan summary{next_frame_, 0, scan_points_,
                                       static_cast<std::uint64_t>(elapsed_s * 1e6)};
      emit(p::MessageType::kEndOfScan, drivers::encode(summary));
      scanning_ = false;
      return;
    }
    // Pacing: frame k is due at k / n of the scan duration.
    if (settings_.scan_duration_s > 0.0 &&
        elapsed_s < settings_.scan_duration_s * double(next_frame_) / double(frames_.size()))
      return;
    if (fault_due(f.unplug_at_fraction)) {
      event_ = DeviceEvent::kUnplug;
      return;
    }
    if (fault_due(f.stall_at_fraction)) {
      stalled_ = true;
      return;
    }
    if (fault_due(f.halt_at_fraction)) event_ = DeviceEvent::kHaltIn;
    if (fault_due(f.wrong_sequence_at_fraction)) ++sequence_;
    if (fault_due(f.skip_frame_at_fraction)) {
      ++next_frame_;  // measured but never sent: the data index jumps, the sequence does not
      continue;
    }
    const std::size_t start = out_.size();
    emit(type, frames_[next_frame_]);
    if (fault_due(f.corrupt_crc_at_fraction)) out_[start + p::kHeaderBytes + 2] ^= 0x5A;
    frames_[next_frame_].clear();
    frames_[next_frame_].shrink_to_fit();
    ++next_frame_;
  }
}

std::size_t ScannerDevice::send(std::vector<std::uint8_t>& out, std::size_t max_bytes) {
  produce_due_frames();
  const std::size_t n = std::min(max_bytes, out_.size() - out_read_);
  out.insert(out.end(), out_.begin() + static_cast<std::ptrdiff_t>(out_read_),
             out_.begin() + static_cast<std::ptrdiff_t>(out_read_ + n));
  out_read_ += n;
  if (out_read_ == out_.size()) {
    out_.clear();
    out_read_ = 0;
  } else if (out_read_ > kFifoBytes) {
    out_.erase(out_.begin(), out_.begin() + static_cast<std::ptrdiff_t>(out_read_));
    out_read_ = 0;
  }
  return n;
}

DeviceEvent ScannerDevice::take_event() { return std::exchange(event_, DeviceEvent::kNone); }

}  // namespace springscan::simulators
