#pragma once
// Command-line options of springscan-scanner-sim (scanner_sim_main.cpp), parsed into the
// simulator's settings, and the part surface they name.

#include <string>
#include <vector>

#include "analysis/core/expected.hpp"
#include "analysis/core/point_cloud.hpp"
#include "simulators/scanner_device.hpp"

namespace springscan::simulators {

struct SimOptions {
  bool help = false;                   ///< --help was given
  ScannerDeviceSettings device;        ///< kind, identity, pattern, noise, duration, faults
  std::string part_path;               ///< --part: a point file of the part surface (part frame)
  std::string profile = "hat";         ///< --profile: an analytic sheet part when no --part
  std::vector<double> springback_deg;  ///< --springback: per bend of the analytic part
  int surface_points = 150000;         ///< dense samples of the analytic part
  double replug_after_s = 1.0;         ///< after an unplug fault; < 0: stay unplugged
  std::vector<std::string> command;    ///< after "--": the program to run under the emulation
};

/// Parses argv; errors name the option and the value.
analysis::Expected<SimOptions> parse_sim_options(int argc, char** argv);
/// The --help text.
std::string sim_usage();
/// The dense surface cloud of the part: the --part file, or the analytic --profile bent by
/// --springback (simulators/parts/sheet_part.hpp).
analysis::Expected<analysis::PointCloud> load_part_surface(const SimOptions& options);

}  // namespace springscan::simulators
