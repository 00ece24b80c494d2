#pragma once
// The GenICam scanner driver: a 3D line profiler (GigE Vision or USB3 Vision) through Aravis,
// set up with the SFNC Scan3d features and read as range lines (docs/device-protocol.md,
// "GenICam 3D line profilers"). Aravis and GLib stay inside genicam_scanner.cpp.

#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "drivers/conversion.hpp"
#include "drivers/genicam/range_lines.hpp"
#include "drivers/scanner.hpp"

namespace springscan::drivers::genicam {

struct GenicamSettings {
  std::string camera_id;  ///< Aravis device id or IP address; "": the first camera found
  RangeFormat pixel_format = RangeFormat::kCoord3dC16;  ///< PixelFormat set before each scan
  std::string component = "Range";  ///< ComponentSelector entry enabled, when the camera has one
  std::string output_mode;          ///< Scan3dOutputMode set before each scan; "": leave it
  int width = 0;                    ///< points per line (Width); 0: as the camera is
  int lines_per_frame = 16;         ///< lines per frame (Height)
  int scan_lines = 500;             ///< lines one scan acquires
  double line_step_mm = 0.0;        ///< travel per line (an encoder-triggered line); 0: from speed
  double speed_mm_s = 0.0;          ///< travel speed, with the line rate, when line_step_mm is 0
  double line_rate_hz = 0.0;        ///< lines per second; 0: the camera's AcquisitionLineRate
  int max_lost_frames = 0;      ///< frames a scan may lose (their lines stay empty), then it fails
  int frame_timeout_ms = 2000;  ///< longest wait for the next frame
  int buffers = 16;             ///< stream buffers queued to Aravis
  /// Further features, set by name in this order before the scan (ExposureTime, ...).
  std::vector<std::pair<std::string, std::string>> features;
  LaserCalibration calibration;  ///< the profile plane and motion axis in the part frame
};

/// A readable reason when the settings cannot work (motion unset, sizes out of range), or "".
std::string validate(const GenicamSettings& settings);

/// The GenICam features the driver needs for `settings`, by name.
std::vector<std::string> required_features(const GenicamSettings& settings);

/// Counters of the last scan.
struct GenicamOutcome {
  std::int64_t frames = 0;       ///< frames received complete
  std::int64_t lost_frames = 0;  ///< frames missing or incomplete
  std::int64_t lines = 0;        ///< lines the scan covered (received or lost)
  std::size_t points = 0;        ///< valid points kept
  double line_step_mm = 0.0;     ///< the motion per line used
};

/// Owns its camera while it is open. Thread safety: one thread at a time (the Scanner contract).
/// A camera that stops answering is closed and reported as kDeviceGone, like an unplugged USB
/// head; identify() opens it again when it is back.
class GenicamScanner final : public Scanner {
 public:
  explicit GenicamScanner(GenicamSettings settings);
  ~GenicamScanner() override;
  GenicamScanner(const GenicamScanner&) = delete;
  GenicamScanner& operator=(const GenicamScanner&) = delete;

  analysis::Expected<DeviceInfo> identify() override;
  analysis::Expected<analysis::PointCloud> scan(const ScanProgress& progress) override;
  bool online() const override;
  std::string last_scan_note() const override;
  const GenicamOutcome& last_outcome() const { return outcome_; }

 private:
  class Camera;  // the open Aravis camera (genicam_scanner.cpp)
  /// The acquisition proper, on a configured camera; `gone` when the camera stopped answering.
  analysis::Expected<analysis::PointCloud> acquire(const RangeScaling& scaling, double step_mm,
                                                   const ScanProgress& progress, bool& gone);
  GenicamSettings settings_;
  std::unique_ptr<Camera> camera_;
  DeviceInfo info_;
  GenicamOutcome outcome_;
};

}  // namespace springscan::drivers::genicam
