#pragma once
// The laser line scanner driver: profiles over USB (docs/device-protocol.md §4.1) mapped into
// part coordinates with the profile-plane calibration and the motion axis.

#include <optional>

#include "drivers/conversion.hpp"
#include "drivers/device_link.hpp"
#include "drivers/scanner.hpp"

namespace springscan::drivers {

struct LaserScannerSettings {
  LinkSettings link;                          ///< device selection (VID/PID/serial), timeouts
  LaserCalibration calibration;               ///< sensor plane and motion axis in the part frame
  std::optional<DeviceConfig> device_config;  ///< sent before each scan when set
};

/// Owns its device link. Thread safety: one thread at a time (the Scanner contract).
class LaserLineScanner final : public Scanner {
 public:
  explicit LaserLineScanner(const LaserScannerSettings& settings);
  analysis::Expected<DeviceInfo> identify() override;
  analysis::Expected<analysis::PointCloud> scan(const ScanProgress& progress) override;
  bool online() const override { return link_.online(); }
  /// Counters of the last successful scan.
  const ScanOutcome& last_outcome() const { return outcome_; }
  const DeviceLink& link() const { return link_; }

 private:
  LaserScannerSettings settings_;
  DeviceLink link_;
  ScanOutcome outcome_;
};

/// The device identity as the Scanner interface reports it.
DeviceInfo to_device_info(const Identity& identity);

}  // namespace springscan::drivers
