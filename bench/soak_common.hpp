#pragma once
// What both station_soak modes share: the emulated scanner they run springscand against, and
// what they measure of springscand from outside: its RSS, open fds and CPU time (from /proc),
// and percentiles of the figures they collect.

#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "simulators/parts/demo_hat.hpp"
#include "simulators/parts/sheet_part.hpp"
#include "simulators/usb_emulator.hpp"

namespace springscan::bench {

/// The q-quantile (0..1, nearest rank) of `v`; 0 for an empty `v`.
inline double percentile(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1, static_cast<std::size_t>(q * static_cast<double>(v.size())))];
}

struct Usage {
  long rss_kb = 0;
  long fds = 0;
  double cpu_s = 0.0;  ///< user + system
};

/// The process's resident set, open descriptors and CPU time; zeros when it is gone.
inline Usage usage_of(pid_t pid) {
  namespace fs = std::filesystem;
  Usage u;
  const std::string proc = "/proc/" + std::to_string(pid);
  std::ifstream status(proc + "/status");
  for (std::string line; std::getline(status, line);) {
    if (line.rfind("VmRSS:", 0) == 0) u.rss_kb = std::stol(line.substr(6));
  }
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(proc + "/fd", ec)) {
    (void)e;
    ++u.fds;
  }
  std::ifstream stat_file(proc + "/stat");
  const std::string stat((std::istreambuf_iterator<char>(stat_file)), {});
  if (stat.empty()) return u;
  std::istringstream fields(stat.substr(stat.rfind(')') + 2));  // after "pid (comm) "
  std::string field;
  unsigned long utime = 0, stime = 0;
  for (int i = 3; fields >> field; ++i) {  // fields 14 and 15 of proc(5)
    if (i == 14) utime = std::stoul(field);
    if (i == 15) stime = std::stoul(field);
  }
  u.cpu_s = static_cast<double>(utime + stime) / static_cast<double>(sysconf(_SC_CLK_TCK));
  return u;
}

/// The emulated USB laser scanner over the demo hat as produced (springback 1.5, 0.8, 1.1,
/// 0.4 deg; demo/README.md), sampled with `surface_points`; errors are printed.
inline std::unique_ptr<simulators::EmulatedUsbScanner> make_demo_scanner(long surface_points,
                                                                         double step_mm,
                                                                         int points_per_profile,
                                                                         double scan_s) {
  parts::ScanSimulationSettings dense;
  dense.point_count = surface_points;
  dense.noise_sigma_mm = 0.0;
  auto surface =
      parts::simulate_scan(parts::demo_hat_profile(), parts::kDemoHatSpringbackDeg, dense);
  if (!surface) {
    std::fprintf(stderr, "%s\n", surface.message().c_str());
    return nullptr;
  }
  simulators::ScannerDeviceSettings device;
  device.laser.step_mm = step_mm;
  device.laser.points_per_profile = points_per_profile;
  device.config.points_per_profile = static_cast<std::uint16_t>(points_per_profile);
  device.scan_duration_s = scan_s;
  auto emulator = simulators::EmulatedUsbScanner::create(device, std::move(*surface));
  if (!emulator) {
    std::fprintf(stderr, "%s\n", emulator.message().c_str());
    return nullptr;
  }
  return std::move(*emulator);
}

}  // namespace springscan::bench
