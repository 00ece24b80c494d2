#pragma once
// The tactile probe driver: probe records over USB (docs/device-protocol.md §4.2), stylus
// radius compensation along the probe direction, mapped into part coordinates.

#include <optional>

#include "drivers/conversion.hpp"
#include "drivers/device_link.hpp"
#include "drivers/scanner.hpp"

namespace springscan::drivers {

struct TactileScannerSettings {
  LinkSettings link;                          ///< device selection (VID/PID/serial), timeouts
  ProbeCalibration calibration;               ///< machine frame in the part frame
  std::optional<DeviceConfig> device_config;  ///< sent before each scan when set
  bool with_normals = true;                   ///< also return -direction as point normals
};

/// Owns its device link. Thread safety: one thread at a time (the Scanner contract).
class TactileProbeScanner final : public Scanner {
 public:
  explicit TactileProbeScanner(const TactileScannerSettings& settings);
  analysis::Expected<DeviceInfo> identify() override;
  analysis::Expected<analysis::PointCloud> scan(const ScanProgress& progress) override;
  bool online() const override { return link_.online(); }
  const ScanOutcome& last_outcome() const { return outcome_; }
  const DeviceLink& link() const { return link_; }

 private:
  TactileScannerSettings settings_;
  DeviceLink link_;
  ScanOutcome outcome_;
};

}  // namespace springscan::drivers
