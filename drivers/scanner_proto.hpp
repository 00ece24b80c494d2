#pragma once
// The scanner named by the daemon config (proto ScannerConfig) as a drivers::Scanner: the one
// place that converts that message into driver settings (STYLE.md §1: only *_proto.cpp files
// convert). Settings start from the C++ defaults and take only the fields the message sets.

#include <memory>

#include "analysis/core/expected.hpp"
#include "drivers/genicam/genicam_scanner.hpp"
#include "drivers/laser_scanner.hpp"
#include "drivers/tactile_scanner.hpp"
#include "proto/springscan.pb.h"

namespace springscan::drivers {

/// Laser settings from the config. Errors name the field and the value.
analysis::Expected<LaserScannerSettings> laser_settings_from_proto(const v1::ScannerConfig& config);
/// Tactile settings from the config. Errors name the field and the value.
analysis::Expected<TactileScannerSettings> tactile_settings_from_proto(
    const v1::ScannerConfig& config);

/// GenICam settings from the config's genicam section, with laser_calibration and timeout_s.
/// Errors name the field and the value.
analysis::Expected<genicam::GenicamSettings> genicam_settings_from_proto(
    const v1::ScannerConfig& config);

/// The driver for a genicam section (a GenICam profiler through Aravis), else for `config.kind`
/// (LASER_LINE, the default when unset, or TACTILE_PROBE), not yet opened: it opens the device on
/// first use and again after an unplug. The only way from a config to a driver: the daemon
/// (daemon/main.cpp) and `springscan scan` both call it, so the laser calibration and
/// t_part_machine reach every scan. Errors name the field and the value.
analysis::Expected<std::unique_ptr<Scanner>> make_scanner(const v1::ScannerConfig& config);

/// The error make_scanner(config) would return, without constructing a driver (no libusb
/// context): for checking a config at load (springscand --check). true when it is usable.
analysis::Expected<bool> check_scanner_config(const v1::ScannerConfig& config);

}  // namespace springscan::drivers
