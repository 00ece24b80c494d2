#include "drivers/scanner_proto.hpp"

#include <algorithm>
#include <cmath>
#include <string>
#include <variant>

namespace springscan::drivers {
namespace {

// Every failure here is a config field out of range.
analysis::Error fail(std::string message) {
  return analysis::fail(analysis::ErrorCode::kInvalidSettings, std::move(message));
}

// VID/PID/serial/timeout shared by both kinds; `product_id` is the kind's default PID.
analysis::Expected<LinkSettings> link_from_proto(const v1::ScannerConfig& c,
                                                 std::uint16_t product_id) {
  LinkSettings link;
  link.usb.product_id = product_id;
  if (c.has_vendor_id()) {
    if (c.vendor_id() == 0 || c.vendor_id() > 0xFFFF)
      return fail("scanner.vendor_id = " + std::to_string(c.vendor_id()) + " (1..65535)");
    link.usb.vendor_id = static_cast<std::uint16_t>(c.vendor_id());
  }
  if (c.has_product_id()) {
    if (c.product_id() == 0 || c.product_id() > 0xFFFF)
      return fail("scanner.product_id = " + std::to_string(c.product_id()) + " (1..65535)");
    link.usb.product_id = static_cast<std::uint16_t>(c.product_id());
  }
  if (c.has_serial()) link.usb.serial = c.serial();
  if (c.has_timeout_s()) {
    if (!(c.timeout_s() > 0.0 && c.timeout_s() <= 3600.0))
      return fail("scanner.timeout_s = " + std::to_string(c.timeout_s()) + " (0 < s <= 3600)");
    link.data_timeout_ms = static_cast<int>(std::lround(c.timeout_s() * 1000.0));
  }
  return link;
}

analysis::Vec3 vec(const v1::Vec3& v) { return {v.x(), v.y(), v.z()}; }

}  // namespace

analysis::Expected<LaserScannerSettings> laser_settings_from_proto(const v1::ScannerConfig& c) {
  auto link = link_from_proto(c, protocol::kProductIdLaser);
  if (!link) return link.error();
  LaserScannerSettings s;
  s.link = *link;
  if (c.has_laser_calibration()) {
    const auto& k = c.laser_calibration();
    if (k.has_origin_mm()) s.calibration.origin_mm = vec(k.origin_mm());
    if (k.has_x_axis()) s.calibration.x_axis = vec(k.x_axis());
    if (k.has_z_axis()) s.calibration.z_axis = vec(k.z_axis());
    if (k.has_motion_axis()) s.calibration.motion_axis = vec(k.motion_axis());
  }
  if (const std::string bad = validate(s.calibration); !bad.empty())
    return fail("scanner.laser_calibration: " + bad);
  return s;
}

analysis::Expected<TactileScannerSettings> tactile_settings_from_proto(const v1::ScannerConfig& c) {
  auto link = link_from_proto(c, protocol::kProductIdTactile);
  if (!link) return link.error();
  TactileScannerSettings s;
  s.link = *link;
  if (c.t_part_machine_size() != 0) {
    if (c.t_part_machine_size() != 16)
      return fail("scanner.t_part_machine has " + std::to_string(c.t_part_machine_size()) +
                  " numbers, expected 16 (row-major 4x4)");
    analysis::Transform::MatrixType m;
    for (int i = 0; i < 16; ++i) m(i / 4, i % 4) = c.t_part_machine(i);
    const analysis::Mat3 R = m.topLeftCorner<3, 3>();
    if (!m.allFinite() || !(R.transpose() * R).isApprox(analysis::Mat3::Identity(), 1e-6) ||
        R.determinant() < 0.0 || !m.row(3).isApprox(Eigen::RowVector4d(0, 0, 0, 1)))
      return fail("scanner.t_part_machine is not a rigid transform");
    s.calibration.T_part_machine.matrix() = m;
  }
  return s;
}

analysis::Expected<genicam::GenicamSettings> genicam_settings_from_proto(
    const v1::ScannerConfig& c) {
  if (c.kind() == v1::ScannerConfig::TACTILE_PROBE)
    return fail("scanner.genicam: a GenICam profiler is a laser line scanner, not TACTILE_PROBE");
  auto laser = laser_settings_from_proto(c);  // the calibration and the timeout, checked
  if (!laser) return laser.error();
  const v1::GenicamConfig& g = c.genicam();
  genicam::GenicamSettings s;
  s.calibration = laser->calibration;
  if (c.has_timeout_s()) s.frame_timeout_ms = laser->link.data_timeout_ms;
  if (g.has_camera_id()) s.camera_id = g.camera_id();
  if (g.has_pixel_format()) {
    using F = genicam::RangeFormat;
    const auto known = {F::kCoord3dC16, F::kCoord3dAbc32f, F::kMono16};
    const auto found = std::find_if(known.begin(), known.end(),
                                    [&](F f) { return to_string(f) == g.pixel_format(); });
    if (found == known.end())
      return fail("scanner.genicam.pixel_format = '" + g.pixel_format() +
                  "' (Coord3D_C16, Coord3D_ABC32f or Mono16)");
    s.pixel_format = *found;
  }
  if (g.has_component()) s.component = g.component();
  if (g.has_output_mode()) s.output_mode = g.output_mode();
  if (g.has_width()) s.width = g.width();
  if (g.has_lines_per_frame()) s.lines_per_frame = g.lines_per_frame();
  if (g.has_scan_lines()) s.scan_lines = g.scan_lines();
  if (g.has_line_step_mm()) s.line_step_mm = g.line_step_mm();
  if (g.has_speed_mm_s()) s.speed_mm_s = g.speed_mm_s();
  if (g.has_line_rate_hz()) s.line_rate_hz = g.line_rate_hz();
  if (g.has_max_lost_frames()) s.max_lost_frames = g.max_lost_frames();
  for (const v1::GenicamFeature& f : g.features()) s.features.emplace_back(f.name(), f.value());
  if (const std::string bad = validate(s); !bad.empty()) return fail("scanner." + bad);
  return s;
}

namespace {

// The driver settings for the config: what make_scanner builds from and check_scanner_config
// checks.
using KindSettings =
    std::variant<LaserScannerSettings, TactileScannerSettings, genicam::GenicamSettings>;

analysis::Expected<KindSettings> settings_for_kind(const v1::ScannerConfig& c) {
  if (c.has_genicam()) {
    auto s = genicam_settings_from_proto(c);
    if (!s) return s.error();
    return KindSettings(std::move(*s));
  }
  switch (c.kind()) {
    case v1::ScannerConfig::KIND_UNSPECIFIED:  // the default kind, like the other defaults
    case v1::ScannerConfig::LASER_LINE: {
      auto s = laser_settings_from_proto(c);
      if (!s) return s.error();
      return KindSettings(std::move(*s));
    }
    case v1::ScannerConfig::TACTILE_PROBE: {
      auto s = tactile_settings_from_proto(c);
      if (!s) return s.error();
      return KindSettings(std::move(*s));
    }
    default:
      return fail("scanner.kind = " + std::to_string(c.kind()) + " (LASER_LINE or TACTILE_PROBE)");
  }
}

}  // namespace

analysis::Expected<bool> check_scanner_config(const v1::ScannerConfig& c) {
  auto settings = settings_for_kind(c);
  if (!settings) return settings.error();
  return true;
}

analysis::Expected<std::unique_ptr<Scanner>> make_scanner(const v1::ScannerConfig& c) {
  auto settings = settings_for_kind(c);
  if (!settings) return settings.error();
  if (const auto* laser = std::get_if<LaserScannerSettings>(&*settings))
    return std::unique_ptr<Scanner>(std::make_unique<LaserLineScanner>(*laser));
  if (auto* genicam = std::get_if<genicam::GenicamSettings>(&*settings))
    return std::unique_ptr<Scanner>(std::make_unique<genicam::GenicamScanner>(std::move(*genicam)));
  return std::unique_ptr<Scanner>(
      std::make_unique<TactileProbeScanner>(std::get<TactileScannerSettings>(*settings)));
}

}  // namespace springscan::drivers
