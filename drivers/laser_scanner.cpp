#include "drivers/laser_scanner.hpp"

namespace springscan::drivers {
namespace {

namespace p = protocol;
using analysis::ErrorCode;
using analysis::fail;

}  // namespace

DeviceInfo to_device_info(const Identity& identity) {
  return DeviceInfo{identity.model, identity.serial, identity.firmware, to_string(identity.kind)};
}

LaserLineScanner::LaserLineScanner(const LaserScannerSettings& settings)
    : settings_(settings), link_(settings.link) {}

analysis::Expected<DeviceInfo> LaserLineScanner::identify() {
  auto id = link_.connect();
  if (!id) return id.error();
  if (id->kind != p::ScannerKind::kLaserLine)
    return fail(ErrorCode::kInvalidSettings,
                "scanner " + id->serial + ": is a " + to_string(id->kind) +
                    ", the laser line driver needs a laser_line scanner");
  return to_device_info(*id);
}

analysis::Expected<analysis::PointCloud> LaserLineScanner::scan(const ScanProgress& progress) {
  if (const std::string bad = validate(settings_.calibration); !bad.empty())
    return fail(ErrorCode::kInvalidSettings, bad);
  auto info = identify();
  if (!info) return info.error();
  if (settings_.device_config) {
    if (auto c = link_.set_config(*settings_.device_config); !c) return c.error();
  }
  analysis::PointCloud cloud;
  bool reserved = false;
  std::uint32_t next_index = 0;
  const FrameHandler handler = [&](const FrameView& frame) -> std::optional<analysis::Error> {
    auto profile = decode_laser_profile(frame.payload);
    if (!profile) return profile.error();
    if (profile->index != next_index)
      return fail(ErrorCode::kSequenceGap, "profile " + std::to_string(profile->index) +
                                               " out of order, expected " +
                                               std::to_string(next_index));
    ++next_index;
    if (!reserved) {
      // Bounded by the §6 limit, checked when the scan-started reply was decoded.
      cloud.points.reserve(link_.last_started().expected_points);
      reserved = true;
    }
    if (cloud.points.size() + profile->count > p::kMaxScanPoints)
      return fail(ErrorCode::kProtocolError,
                  "scan exceeds " + std::to_string(p::kMaxScanPoints) + " points (§6)");
    append_laser_profile(*profile, settings_.calibration, cloud.points);
    return std::nullopt;
  };
  auto outcome = link_.scan(p::MessageType::kLaserProfile, handler, progress);
  if (!outcome) return outcome.error();
  outcome_ = *outcome;
  return cloud;
}

}  // namespace springscan::drivers
