#pragma once
// The scanner as the daemon and the CLI see it: one interface for the tactile probe and the
// laser line scanner (DESIGN.md "drivers/"). Implementations live in drivers/; the daemon owns
// exactly one and calls it from one thread at a time.

#include <atomic>
#include <functional>
#include <string>

#include "analysis/core/expected.hpp"
#include "analysis/core/point_cloud.hpp"

namespace springscan::drivers {

struct DeviceInfo {
  std::string model;
  std::string serial;
  std::string firmware;
  std::string kind;  ///< "laser_line" or "tactile_probe"
};

/// Called during a scan with the share done (0..1); return false to cancel.
using ScanProgress = std::function<bool(double fraction_done)>;

class Scanner {
 public:
  virtual ~Scanner() = default;
  /// Opens the device if needed and reads its identity.
  virtual analysis::Expected<DeviceInfo> identify() = 0;
  /// Runs one complete scan and returns the points in part coordinates (mm). A scan that is
  /// interrupted (unplug, timeout, corrupt data, cancel) returns an error and no partial cloud.
  virtual analysis::Expected<analysis::PointCloud> scan(const ScanProgress& progress) = 0;
  /// True while the device is present and open.
  virtual bool online() const = 0;
  /// What the last successful scan had to do without (frames the network lost, within the
  /// limit set), for the station's log; empty when the scan came whole.
  virtual std::string last_scan_note() const { return {}; }
};

}  // namespace springscan::drivers
