#include "drivers/tactile_scanner.hpp"

#include "drivers/laser_scanner.hpp"

namespace springscan::drivers {
namespace {

namespace p = protocol;
using analysis::ErrorCode;
using analysis::fail;

}  // namespace

TactileProbeScanner::TactileProbeScanner(const TactileScannerSettings& settings)
    : settings_(settings), link_(settings.link) {}

analysis::Expected<DeviceInfo> TactileProbeScanner::identify() {
  auto id = link_.connect();
  if (!id) return id.error();
  if (id->kind != p::ScannerKind::kTactileProbe)
    return fail(ErrorCode::kInvalidSettings, "scanner " + id->serial + ": is a " +
                                                 to_string(id->kind) +
                                                 ", the tactile driver needs a tactile_probe");
  return to_device_info(*id);
}

analysis::Expected<analysis::PointCloud> TactileProbeScanner::scan(const ScanProgress& progress) {
  auto info = identify();
  if (!info) return info.error();
  if (settings_.device_config) {
    if (auto c = link_.set_config(*settings_.device_config); !c) return c.error();
  }
  analysis::PointCloud cloud;
  std::uint32_t next_index = 0;
  const FrameHandler handler = [&](const FrameView& frame) -> std::optional<analysis::Error> {
    auto batch = decode_probe_batch(frame.payload);
    if (!batch) return batch.error();
    if (batch->first_index != next_index)
      return fail(ErrorCode::kSequenceGap, "probe point " + std::to_string(batch->first_index) +
                                               " out of order, expected " +
                                               std::to_string(next_index));
    next_index += batch->count;
    if (cloud.points.size() + batch->count > p::kMaxScanPoints)
      return fail(ErrorCode::kProtocolError,
                  "scan exceeds " + std::to_string(p::kMaxScanPoints) + " points (§6)");
    append_probe_batch(*batch, settings_.calibration, cloud.points,
                       settings_.with_normals ? &cloud.normals : nullptr);
    return std::nullopt;
  };
  auto outcome = link_.scan(p::MessageType::kProbePoints, handler, progress);
  if (!outcome) return outcome.error();
  outcome_ = *outcome;
  return cloud;
}

}  // namespace springscan::drivers
