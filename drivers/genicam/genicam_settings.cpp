// GenicamSettings checks and the feature list: no Aravis here, so tests run without a camera.
#include <cmath>

#include "drivers/genicam/genicam_scanner.hpp"

namespace springscan::drivers::genicam {

std::string validate(const GenicamSettings& s) {
  if (to_string(s.pixel_format).empty()) return "genicam.pixel_format: not a range format";
  if (s.width < 0 || s.width > 65535)
    return "genicam.width = " + std::to_string(s.width) + " (0: the camera's, or 1..65535)";
  if (s.lines_per_frame < 1 || s.lines_per_frame > 65535)
    return "genicam.lines_per_frame = " + std::to_string(s.lines_per_frame) + " (1..65535)";
  if (s.scan_lines < 1 || s.scan_lines > 10000000)
    return "genicam.scan_lines = " + std::to_string(s.scan_lines) + " (1..10000000)";
  if (!(s.line_step_mm >= 0.0) || !std::isfinite(s.line_step_mm))
    return "genicam.line_step_mm = " + std::to_string(s.line_step_mm) + " (>= 0)";
  if (!(s.speed_mm_s >= 0.0) || !std::isfinite(s.speed_mm_s))
    return "genicam.speed_mm_s = " + std::to_string(s.speed_mm_s) + " (>= 0)";
  if (!(s.line_rate_hz >= 0.0) || !std::isfinite(s.line_rate_hz))
    return "genicam.line_rate_hz = " + std::to_string(s.line_rate_hz) + " (>= 0)";
  // The motion axis needs the travel per line: an encoder step, or a speed and a line rate.
  if (s.line_step_mm == 0.0 && s.speed_mm_s == 0.0)
    return "genicam: set line_step_mm (lines triggered by an encoder) or speed_mm_s (with the "
           "line rate) so that lines have their place along the motion";
  if (s.max_lost_frames < 0)
    return "genicam.max_lost_frames = " + std::to_string(s.max_lost_frames);
  if (s.frame_timeout_ms < 1) return "genicam frame timeout must be positive";
  if (s.buffers < 2 || s.buffers > 1024)
    return "genicam.buffers = " + std::to_string(s.buffers) + " (2..1024)";
  for (const auto& [name, value] : s.features) {
    if (name.empty()) return "genicam.features: a feature without a name (value '" + value + "')";
  }
  return validate(s.calibration);
}

std::vector<std::string> required_features(const GenicamSettings& s) {
  std::vector<std::string> names{"Width",
                                 "Height",
                                 "PixelFormat",
                                 "PayloadSize",
                                 "AcquisitionStart",
                                 "AcquisitionStop",
                                 "Scan3dCoordinateSelector",
                                 "Scan3dCoordinateScale",
                                 "Scan3dCoordinateOffset"};
  if (!s.output_mode.empty()) names.push_back("Scan3dOutputMode");
  if (s.line_step_mm == 0.0 && s.line_rate_hz == 0.0) names.push_back("AcquisitionLineRate");
  for (const auto& feature : s.features) names.push_back(feature.first);
  return names;
}

}  // namespace springscan::drivers::genicam
