#pragma once
// The simulated scanner's firmware: the device side of docs/device-protocol.md, independent of
// USB. Bytes from bulk OUT go in through receive(); bytes for bulk IN come out of send(). The
// scan data are measured from the part when a scan starts (scan_pattern.hpp), paced over the
// scan duration, and the faults chosen in the settings are injected on the way out.
//
// Thread safety: none; the USB emulation serialises all calls under its own lock.

#include <chrono>
#include <cstdint>
#include <random>
#include <string>
#include <vector>

#include "drivers/codec.hpp"
#include "drivers/messages.hpp"
#include "simulators/scan_pattern.hpp"

namespace springscan::simulators {

/// Faults, each at a share of the scan's data frames (< 0: off). Each fires once per device
/// (until it is plugged in again), so the scan after a fault can succeed.
struct DeviceFaults {
  double unplug_at_fraction = -1.0;          ///< the device disconnects
  double stall_at_fraction = -1.0;           ///< the device stops sending until stop-scan
  double halt_at_fraction = -1.0;            ///< the bulk IN endpoint halts (STALL) once
  double corrupt_crc_at_fraction = -1.0;     ///< one data frame goes out with a bad CRC
  double wrong_sequence_at_fraction = -1.0;  ///< one data frame skips a sequence number
  /// One data frame is never sent while the frame sequence numbers stay contiguous: the host
  /// sees the next profile (or probe batch) index, "profile N out of order".
  double skip_frame_at_fraction = -1.0;
  /// With halt_at_fraction: the halt cannot be cleared (CLEAR_HALT fails with EPIPE) until the
  /// device is reset or plugged in again; the host sees a stalled endpoint.
  bool halt_sticks = false;
};

struct ScannerDeviceSettings {
  drivers::Identity identity{drivers::protocol::ScannerKind::kLaserLine, "SL-200 simulated",
                             "SIM0001", "1.0.0"};
  drivers::DeviceConfig config;  ///< the configuration at power-on
  LaserPatternSettings laser;    ///< laser line pattern (kind kLaserLine)
  ProbePatternSettings probe;    ///< probe grid (kind kTactileProbe)
  NoiseSettings noise;           ///< measurement noise, outliers, missing points
  double scan_duration_s = 0.0;  ///< data spread evenly over this time; 0: as fast as read
  DeviceFaults faults;           ///< injected faults
  std::uint32_t seed = 1;        ///< noise seed; each scan continues the sequence
  /// > 0: each scan finds the part placed anew, as a loader puts it in its fixture again: moved
  /// by up to this (uniform per axis, mm) and turned by up to replace_deg about a random axis
  /// through the surface's centroid. The gauge studies re-place the part each cycle.
  double replace_mm = 0.0;
  double replace_deg = 0.0;
};

/// `surface` as placed anew within `settings.replace_mm` / `replace_deg` (drawn from `rng`);
/// unchanged when both are 0.
analysis::PointCloud replaced(const analysis::PointCloud& surface,
                              const ScannerDeviceSettings& settings, std::mt19937& rng);

/// Where the emulation should act on a fault that is not just bytes.
enum class DeviceEvent { kNone, kUnplug, kHaltIn };

class ScannerDevice {
 public:
  /// `surface` is a dense point cloud of the part in the part frame (mm).
  ScannerDevice(const ScannerDeviceSettings& settings, analysis::PointCloud surface);

  /// Bytes the host wrote on bulk OUT.
  void receive(std::span<const std::uint8_t> bytes);
  /// Moves up to `max_bytes` of what the device has to send now into `out` (appended).
  /// Returns the number of bytes; 0 when nothing is due yet.
  std::size_t send(std::vector<std::uint8_t>& out, std::size_t max_bytes);
  /// A fault that the USB layer has to carry out (unplug, endpoint halt); cleared when read.
  DeviceEvent take_event();
  /// The endpoint halt of this device cannot be cleared (DeviceFaults::halt_sticks).
  bool halt_sticks() const { return settings_.faults.halt_sticks; }
  /// Replaces the faults of this device (a fault campaign arms one per scan without a
  /// replug). Fractions count the frames of the next scan that starts, or of the running one.
  void arm_faults(const DeviceFaults& faults) { settings_.faults = faults; }
  /// Replaces the laser pattern (the heads' mounts) from the next scan on: a head that moved.
  void set_laser_pattern(const LaserPatternSettings& laser) { settings_.laser = laser; }

  bool scanning() const { return scanning_; }
  std::uint32_t scans_started() const { return scan_id_; }
  std::uint32_t frames_sent() const { return next_frame_; }
  std::uint32_t frames_total() const { return static_cast<std::uint32_t>(frames_.size()); }

 private:
  void handle(const drivers::FrameView& frame);
  void start_scan(std::uint32_t command_sequence);
  void stop_scan();
  void emit(drivers::protocol::MessageType type, std::span<const std::uint8_t> payload);
  void emit_error(drivers::protocol::DeviceErrorCode code, std::uint32_t command_sequence,
                  const std::string& message);
  void produce_due_frames();
  bool fault_due(double& fraction);

  ScannerDeviceSettings settings_;
  analysis::PointCloud surface_;
  std::mt19937 rng_;
  drivers::FrameDecoder decoder_;
  std::vector<std::uint8_t> out_;
  std::size_t out_read_ = 0;
  std::uint32_t sequence_ = 0;
  std::uint32_t scan_id_ = 0;
  bool scanning_ = false;
  bool stalled_ = false;
  std::vector<std::vector<std::uint8_t>> frames_;  // payloads of the running scan
  std::uint64_t scan_points_ = 0;
  std::uint32_t next_frame_ = 0;
  std::chrono::steady_clock::time_point scan_start_;
  DeviceEvent event_ = DeviceEvent::kNone;
};

}  // namespace springscan::simulators
