// Station figures for docs/performance.md (a figures program, not a timed test): springscand
// as a real process under the emulated USB laser scanner measuring the demo hat profile over
// its whole surface (as scripts/demo.sh; CAD demo/hat-profile.step), the simulated PLC running
// N handshake cycles, and four Modbus clients polling the live block every 10 ms meanwhile.
//   station_soak [--cycles N] [--points-per-profile P] [--step-mm S] [--scan-s T]
//                [--surface-points M]
// Prints: the scan size; trigger -> RESULT_VALID minus the simulated scan time T (cycle 1,
// which loads the CAD model, separately); the Modbus response times of the polling clients,
// all and those answered while the station was ANALYZING; springscand's RSS and open fds
// over the cycles; its CPU time (user + system) per cycle, next to the wall time, since the
// machine may be shared.
//
//   station_soak --faults [--cycles N] [--seed S] [the scan options]
// runs the fault campaign instead (fault_campaign.hpp): N cycles (default 1000), each with no
// fault or a random one, on a small scan; exits non-zero when a failure count is not 0.
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "bench/fault_campaign.hpp"
#include "bench/soak_common.hpp"
#include "proto/springscan.pb.h"
#include "simulators/plc_client.hpp"
#include "simulators/usb_emulator.hpp"
#include "tests/daemon/daemon_process.hpp"
#include "tests/support/test_paths.hpp"

namespace {

using namespace springscan;
using bench::percentile;
using bench::Usage;
using bench::usage_of;
namespace fs = std::filesystem;
namespace regs = daemon::regs;
using Clock = std::chrono::steady_clock;

struct Options {
  int cycles = 20;
  int points_per_profile = 1000;
  double step_mm = 0.4;           // 1000 x 201 profiles over the 80 mm width: ~200k points
  double scan_s = 1.0;            // the simulated scan's duration (device pacing)
  long surface_points = 1200000;  // dense enough that nearly every bin sees the surface
};

/// Response times (ms), split by the station's state in the answer.
struct PollTimes {
  std::mutex mutex;
  std::vector<double> all, analyzing;
};

/// Polls the live block every 10 ms and records each response time until `stop`.
void poll_client(int port, const std::atomic<bool>& stop, PollTimes& times) {
  simulators::PlcClientSettings settings;
  settings.port = port;
  settings.send_heartbeat = false;
  auto client = simulators::PlcClient::connect(settings);
  if (!client) return;
  std::uint16_t live[regs::kLiveCount];
  while (!stop) {
    const auto t0 = Clock::now();
    if (modbus_read_input_registers((*client)->context(), 0, regs::kLiveCount, live) < 0) return;
    const double ms = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
    {
      std::lock_guard lock(times.mutex);
      times.all.push_back(ms);
      if (live[regs::kIrState] == static_cast<std::uint16_t>(regs::State::kAnalyzing))
        times.analyzing.push_back(ms);
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
}

Options parse(int argc, char** argv) {
  Options o;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string arg = argv[i];
    if (arg == "--cycles") o.cycles = std::stoi(argv[i + 1]);
    if (arg == "--points-per-profile") o.points_per_profile = std::stoi(argv[i + 1]);
    if (arg == "--step-mm") o.step_mm = std::stod(argv[i + 1]);
    if (arg == "--scan-s") o.scan_s = std::stod(argv[i + 1]);
    if (arg == "--surface-points") o.surface_points = std::stol(argv[i + 1]);
  }
  return o;
}

/// --faults: the campaign's settings, its small-scan defaults overridden by the options given.
int run_campaign(int argc, char** argv) {
  bench::CampaignSettings c;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--keep") c.keep_files = true;
    if (i + 1 == argc) break;
    if (arg == "--cycles") c.cycles = std::stoi(argv[i + 1]);
    if (arg == "--seed") c.seed = static_cast<std::uint32_t>(std::stoul(argv[i + 1]));
    if (arg == "--points-per-profile") c.points_per_profile = std::stoi(argv[i + 1]);
    if (arg == "--step-mm") c.step_mm = std::stod(argv[i + 1]);
    if (arg == "--scan-s") c.scan_s = std::stod(argv[i + 1]);
    if (arg == "--surface-points") c.surface_points = std::stol(argv[i + 1]);
  }
  return bench::run_fault_campaign(c);
}

}  // namespace

int main(int argc, char** argv) {
  std::signal(SIGPIPE, SIG_IGN);
  for (int i = 1; i < argc; ++i) {
    if (std::string(argv[i]) == "--faults") return run_campaign(argc, argv);
  }
  const Options o = parse(argc, argv);
  const fs::path dir = fs::temp_directory_path() / ("springscan-soak-" + std::to_string(getpid()));
  fs::create_directories(dir);
  auto emulator =
      bench::make_demo_scanner(o.surface_points, o.step_mm, o.points_per_profile, o.scan_s);
  if (!emulator) return 1;
  const std::string config = (dir / "station.textproto").string();
  const std::string reports = (dir / "reports").string();
  std::ofstream(config) << "modbus { bind_address: \"127.0.0.1\" port: 0 }\n"
                           "scanner { kind: LASER_LINE timeout_s: 30 }\n"
                           "parts { part_id: 1 cad_file: \""
                        << springscan::test_paths::source("demo/hat-profile.step")
                        << "\"\n  settings { verdict { tolerance_mm: 0.5 "
                           "angle_tolerance_deg: 2.0 } } }\n"
                        << "report_dir: \"" << reports << "\"\nmodel_cache_dir: \""
                        << (dir / "cache").string()
                        << "\"\nreport_retention: 5\nlog_level: \"error\"\n";
  int result = 0;
  {
    daemon::testing::DaemonProcess station(springscan::test_paths::kSpringscand, config,
                                           dir.string(),
                                           {"LD_PRELOAD=" + simulators::umockdev_preload_library(),
                                            "UMOCKDEV_DIR=" + emulator->root_dir()});
    simulators::PlcClientSettings settings;
    settings.port = station.port();
    settings.step_timeout_s = 300;
    auto plc = simulators::PlcClient::connect(settings);
    if (!plc) return 1;
    (void)(*plc)->wait_for([](const auto& s) { return s.bit(regs::kDiScannerOnline); }, "scanner");
    std::atomic<bool> stop{false};
    PollTimes times;
    std::vector<std::thread> pollers;
    for (int i = 0; i < 4; ++i)
      pollers.emplace_back(poll_client, station.port(), std::cref(stop), std::ref(times));
    std::vector<double> minus_scan, analysis_ms;
    std::vector<std::pair<int, Usage>> samples;
    double first_minus_scan = 0.0;
    Usage after_first;
    const auto soak_start = Clock::now();
    for (int k = 0; k < o.cycles; ++k) {
      auto cycle = (*plc)->run_cycle(static_cast<std::uint16_t>(k + 1), 1);
      if (!cycle || !cycle->accepted || cycle->error_code != 0) {
        std::fprintf(stderr, "cycle %d failed: %s\n", k + 1,
                     cycle ? "not accepted or an error" : cycle.message().c_str());
        result = 1;
        break;
      }
      char name[40];
      std::snprintf(name, sizeof name, "/r%012d/report.pb", k + 1);
      std::ifstream in(reports + name, std::ios::binary);
      v1::InspectionReport report;
      report.ParseFromIstream(&in);
      const double latency = cycle->trigger_to_valid_ms - o.scan_s * 1000.0;
      if (k == 0) {
        first_minus_scan = latency;
        after_first = usage_of(station.pid());
        std::printf("scan points: %lld, verdict %s\n",
                    static_cast<long long>(report.input().scan_points()),
                    report.verdict().pass() ? "pass" : "fail");
      } else {
        minus_scan.push_back(latency);
        analysis_ms.push_back(report.timings_ms().total());
      }
      if (k == 0 || k + 1 == o.cycles || (k + 1) % 50 == 0)
        samples.emplace_back(k + 1, usage_of(station.pid()));
    }
    const double wall_s = std::chrono::duration<double>(Clock::now() - soak_start).count();
    const Usage end = usage_of(station.pid());
    stop = true;
    for (auto& t : pollers) t.join();
    std::printf("cycle 1 (loads the CAD model): trigger->valid minus %.2f s scan: %.0f ms\n",
                o.scan_s, first_minus_scan);
    std::printf(
        "cycles 2..%d: trigger->valid minus scan: median %.0f ms, p95 %.0f ms, max %.0f "
        "ms; analysis (report timings total) median %.0f ms\n",
        o.cycles, percentile(minus_scan, 0.5), percentile(minus_scan, 0.95),
        percentile(minus_scan, 1.0), percentile(analysis_ms, 0.5));
    std::printf("modbus responses %zu: p50 %.2f ms, p99 %.2f ms, max %.2f ms\n", times.all.size(),
                percentile(times.all, 0.5), percentile(times.all, 0.99),
                percentile(times.all, 1.0));
    std::printf("  while ANALYZING %zu: p50 %.2f ms, p99 %.2f ms, max %.2f ms\n",
                times.analyzing.size(), percentile(times.analyzing, 0.5),
                percentile(times.analyzing, 0.99), percentile(times.analyzing, 1.0));
    for (const auto& [cycle, u] : samples)
      std::printf("after cycle %d: RSS %ld kB, open fds %ld\n", cycle, u.rss_kb, u.fds);
    const int later = std::max(1, o.cycles - 1);
    std::printf(
        "springscand CPU: %.2f s for cycles 2..%d (%.0f ms per cycle); wall %.1f s for "
        "all %d cycles\n",
        end.cpu_s - after_first.cpu_s, o.cycles, 1000.0 * (end.cpu_s - after_first.cpu_s) / later,
        wall_s, o.cycles);
  }
  fs::remove_all(dir);
  return result;
}
