// Station figures for docs/performance.md (not a timed test): springscand as a real process
// under the emulated USB laser scanner, the simulated PLC running N handshake cycles, and
// four Modbus clients polling the live block at about 100 requests/s each meanwhile.
//   station_soak [--cycles N] [--points-per-profile P] [--step-mm S]
// Prints: trigger -> RESULT_VALID minus the scan time (median, p95), the Modbus response time
// of the polling clients (p50, p99, max), and the daemon's RSS and open fds over the cycles.
#include <algorithm>
#include <atomic>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>
#include <vector>

#include "analysis/cad_profile.hpp"
#include "analysis/sheet_part.hpp"
#include "proto/springscan.pb.h"
#include "simulators/plc_client.hpp"
#include "simulators/usb_emulator.hpp"
#include "tests/daemon/daemon_process.hpp"

namespace {

using namespace springscan;
namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

double percentile(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1, static_cast<std::size_t>(q * static_cast<double>(v.size())))];
}

std::pair<long, long> rss_kb_and_fds(pid_t pid) {
  long rss = 0;
  std::ifstream status("/proc/" + std::to_string(pid) + "/status");
  for (std::string line; std::getline(status, line);) {
    if (line.rfind("VmRSS:", 0) == 0) rss = std::stol(line.substr(6));
  }
  long fds = 0;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator("/proc/" + std::to_string(pid) + "/fd", ec)) {
    (void)e;
    ++fds;
  }
  return {rss, fds};
}

/// Polls the live block every 10 ms and records each response time (ms) until `stop`.
void poll_client(int port, const std::atomic<bool>& stop, std::vector<double>& times) {
  simulators::PlcClientSettings settings;
  settings.port = port;
  settings.send_heartbeat = false;
  auto client = simulators::PlcClient::connect(settings);
  if (!client) return;
  std::uint16_t live[daemon::regs::kLiveCount];
  while (!stop) {
    const auto t0 = Clock::now();
    if (modbus_read_input_registers((*client)->context(), 0, daemon::regs::kLiveCount, live) < 0) {
      return;
    }
    times.push_back(std::chrono::duration<double, std::milli>(Clock::now() - t0).count());
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
}

}  // namespace

int main(int argc, char** argv) {
  int cycles = 20, points_per_profile = 1024;
  double step_mm = 0.3;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string arg = argv[i];
    if (arg == "--cycles") cycles = std::stoi(argv[i + 1]);
    if (arg == "--points-per-profile") points_per_profile = std::stoi(argv[i + 1]);
    if (arg == "--step-mm") step_mm = std::stod(argv[i + 1]);
  }
  std::signal(SIGPIPE, SIG_IGN);
  const fs::path dir = fs::temp_directory_path() / ("springscan-soak-" + std::to_string(getpid()));
  fs::create_directories(dir);
  const auto nominal = analysis::l_profile(60, 25, 90, 3);
  const std::string cad = (dir / "part.step").string();
  if (!analysis::write_profile_cad(nominal, cad).ok()) return 1;
  analysis::ScanSimulationSettings dense;
  dense.point_count = 600000;
  dense.noise_sigma_mm = 0.0;
  simulators::ScannerDeviceSettings device;
  device.laser.step_mm = step_mm;
  device.laser.points_per_profile = points_per_profile;
  auto emulator =
      simulators::EmulatedUsbScanner::create(device, *analysis::simulate_scan(nominal, {0.5}, dense));
  if (!emulator) {
    std::fprintf(stderr, "%s\n", emulator.message().c_str());
    return 1;
  }
  const std::string config = (dir / "station.textproto").string();
  std::ofstream(config) << "modbus { bind_address: \"127.0.0.1\" port: 0 }\n"
                           "scanner { kind: LASER_LINE }\n"
                           "parts { part_id: 1 cad_file: \"" << cad << "\" }\n"
                           "report_dir: \"reports\"\nreport_retention: 5\nlog_level: \"error\"\n";
  int result = 0;
  {
    daemon::testing::DaemonProcess station(
        SPRINGSCAND_EXE, config, dir.string(),
        {"LD_PRELOAD=" + simulators::umockdev_preload_library(),
         "UMOCKDEV_DIR=" + (*emulator)->root_dir()});
    simulators::PlcClientSettings settings;
    settings.port = station.port();
    settings.step_timeout_s = 300;
    auto plc = simulators::PlcClient::connect(settings);
    if (!plc) return 1;
    (void)(*plc)->wait_for([](const auto& s) { return s.bit(daemon::regs::kDiScannerOnline); },
                           "scanner");
    std::atomic<bool> stop{false};
    std::vector<std::vector<double>> times(4);
    std::vector<std::thread> pollers;
    for (auto& t : times) pollers.emplace_back(poll_client, station.port(), std::cref(stop), std::ref(t));
    std::vector<double> latency_minus_scan, latency;
    std::vector<std::pair<long, long>> usage;
    for (int k = 0; k < cycles; ++k) {
      auto cycle = (*plc)->run_cycle(static_cast<std::uint16_t>(k + 1), 1);
      if (!cycle || !cycle->accepted || cycle->error_code != 0) {
        std::fprintf(stderr, "cycle %d failed\n", k + 1);
        result = 1;
        break;
      }
      // Scan time = cycle time (trigger -> analysis end) minus the analysis' own total.
      springscan::v1::InspectionReport report;
      const auto record = (dir / "reports" / "").string();
      char name[32];
      std::snprintf(name, sizeof name, "r%012d/report.pb", k + 1);
      std::ifstream in(record + name, std::ios::binary);
      report.ParseFromIstream(&in);
      const double scan_ms = report.cycle_time_ms() - report.timings_ms().total();
      latency.push_back(cycle->trigger_to_valid_ms);
      latency_minus_scan.push_back(cycle->trigger_to_valid_ms - scan_ms);
      if (k == 0 || k + 1 == cycles || (k + 1) % 10 == 0) usage.push_back(rss_kb_and_fds(station.pid()));
      if (k == 0) std::printf("scan points: %lld\n", static_cast<long long>(report.input().scan_points()));
    }
    stop = true;
    for (auto& t : pollers) t.join();
    std::vector<double> all;
    for (const auto& t : times) all.insert(all.end(), t.begin(), t.end());
    std::printf("cycles %zu: trigger->valid median %.0f ms; minus scan: median %.0f ms, p95 %.0f ms\n",
                latency.size(), percentile(latency, 0.5), percentile(latency_minus_scan, 0.5),
                percentile(latency_minus_scan, 0.95));
    std::printf("modbus responses %zu: p50 %.2f ms, p99 %.2f ms, max %.2f ms\n", all.size(),
                percentile(all, 0.5), percentile(all, 0.99), percentile(all, 1.0));
    for (std::size_t i = 0; i < usage.size(); ++i) {
      std::printf("usage sample %zu: RSS %ld kB, open fds %ld\n", i, usage[i].first, usage[i].second);
    }
  }
  fs::remove_all(dir);
  return result;
}
