#pragma once
// The fault campaign of station_soak (`--faults`, issue 19 "1,000 cycles with faults"):
// springscand as a real process under the emulated USB laser scanner, restarted by a supervisor
// loop as systemd would, and a simulated PLC running the handshake of
// docs/modbus-register-map.md for N cycles. Each cycle draws, from the seed, no fault or one of
// the faults of FaultKind, and the PLC program recovers as the register map's "Reconnecting"
// and "Error codes" sections tell a PLC programmer to. Counted: crashes, lost, duplicated and
// stale results, the cycle times, springscand's RSS and open fds.

#include <cstdint>

namespace springscan::bench {

struct CampaignSettings {
  int cycles = 1000;
  std::uint32_t seed = 1;  ///< draws the faults and their timing; the same seed, the same draws
  // A small scan, so that a cycle is about the handshake and the faults, not the analysis.
  double step_mm = 2.0;  ///< 41 profiles over the demo hat's 80 mm width
  int points_per_profile = 200;
  double scan_s = 0.3;             ///< the device paces its frames over this (a "mid-scan" exists)
  long surface_points = 100000;    ///< the simulated part's surface
  double scanner_timeout_s = 1.0;  ///< scanner.timeout_s: how long a silent scanner is waited for
  double plc_heartbeat_timeout_s = 1.5;  ///< modbus.plc_heartbeat_timeout_s
  double restart_delay_s = 0.1;          ///< the supervisor's RestartSec
  double unrecovered_after_s = 60.0;     ///< no result or READY this long: the campaign gives up
  bool keep_files = false;  ///< keep the directory (reports, springscand.log) even when clean
};

/// Runs the campaign and prints its figures. Returns 0 when every failure count is 0.
int run_fault_campaign(const CampaignSettings& settings);

}  // namespace springscan::bench
