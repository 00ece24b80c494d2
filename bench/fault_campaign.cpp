// The fault campaign: the cycles, the fault each one draws and how it is injected and repaired.
// The PLC program that rides through them is campaign_plc.cpp; the figures are printed by
// campaign_report.cpp.
#include "bench/fault_campaign.hpp"

#include <csignal>
#include <filesystem>
#include <fstream>
#include <thread>

#include "bench/fault_campaign_internal.hpp"
#include "tests/support/test_paths.hpp"

namespace springscan::bench {

namespace fs = std::filesystem;

const char* fault_name(FaultKind kind) {
  switch (kind) {
    case FaultKind::kNone:
      return "no fault";
    case FaultKind::kUnplug:
      return "unplug mid-scan, replug";
    case FaultKind::kHaltCleared:
      return "endpoint halt, cleared";
    case FaultKind::kStuckHalt:
      return "stalled endpoint (stuck halt)";
    case FaultKind::kBadCrc:
      return "corrupted CRC frame";
    case FaultKind::kSequenceGap:
      return "sequence gap";
    case FaultKind::kScanTimeout:
      return "scanner timeout (silent)";
    case FaultKind::kDropAfterTrigger:
      return "PLC drops after TRIGGER";
    case FaultKind::kDropAfterAck:
      return "PLC drops after TRIG_ACK";
    case FaultKind::kDropWhileBusy:
      return "PLC drops awaiting RESULT_VALID";
    case FaultKind::kDropBeforeAck:
      return "PLC drops before RESULT_ACK";
    case FaultKind::kHeartbeatLoss:
      return "PLC heartbeat loss";
    case FaultKind::kKill:
      return "SIGKILL + supervisor restart";
    case FaultKind::kCount:
      break;
  }
  return "?";
}

Campaign::Campaign(const CampaignSettings& settings, const CampaignPaths& paths,
                   simulators::EmulatedUsbScanner& emulator, Supervisor& station)
    : settings_(settings),
      paths_(paths),
      emulator_(emulator),
      station_(station),
      draws_(settings.seed),
      rng_(settings.seed ^ 0x9E3779B9u) {}

double Campaign::uniform(double lo, double hi) {
  return std::uniform_real_distribution<double>(lo, hi)(rng_);
}

FaultKind Campaign::draw() {
  return static_cast<FaultKind>(std::uniform_int_distribution<int>(0, kFaultKinds - 1)(draws_));
}

bool Campaign::run() {
  for (int k = 1; k <= settings_.cycles; ++k) {
    // Job ids 1..65535, never 0 (0 is what the registers hold after a restart).
    if (!run_cycle(static_cast<std::uint16_t>((k - 1) % 65535 + 1))) return false;
    ++tally_.cycles_run;
    if (k % 100 == 0)
      std::fprintf(stderr, "  %d cycles, %d failures, %d crashes\n", k, tally_.failures(),
                   station_.crashes());
  }
  return true;
}

bool Campaign::run_cycle(std::uint16_t job) {
  kind_ = draw();
  arm_device(FaultKind::kNone);  // a fault armed for a refused trigger must not carry over
  if (!make_ready()) return false;
  arm_device(kind_);
  KindFigures& figures = tally_.kinds[static_cast<int>(kind_)];
  ++figures.cycles;
  const auto start = Clock::now();
  if (trigger(job, kind_)) {
    inject_after_trigger(kind_);
    if (!collect(job, kind_ == FaultKind::kDropBeforeAck)) return false;
  }
  repair_after(kind_);
  figures.cycle_ms.push_back(
      std::chrono::duration<double, std::milli>(Clock::now() - start).count());
  sample_usage();
  return true;
}

void Campaign::arm_device(FaultKind kind) {
  // Each at a random share of the scan's frames, so faults land early, late and in between.
  const double at = uniform(0.15, 0.85);
  simulators::DeviceFaults f;
  switch (kind) {
    case FaultKind::kUnplug:
      f.unplug_at_fraction = at;
      break;
    case FaultKind::kHaltCleared:
      f.halt_at_fraction = at;
      break;
    case FaultKind::kStuckHalt:
      f.halt_at_fraction = at;
      f.halt_sticks = true;
      break;
    case FaultKind::kBadCrc:
      f.corrupt_crc_at_fraction = at;
      break;
    case FaultKind::kSequenceGap:
      f.wrong_sequence_at_fraction = at;
      break;
    case FaultKind::kScanTimeout:
      f.stall_at_fraction = at;
      break;
    default:
      break;
  }
  emulator_.arm_faults(f);
}

void Campaign::inject_after_trigger(FaultKind kind) {
  const double busy_s = settings_.scan_s + 0.3;  // about a cycle's scan and analysis
  switch (kind) {
    case FaultKind::kDropAfterAck:
      drop_connection();
      pause_disconnected();
      break;
    case FaultKind::kDropWhileBusy:
      idle(uniform(0.0, busy_s));
      drop_connection();
      pause_disconnected();
      break;
    case FaultKind::kHeartbeatLoss:
      // The PLC keeps polling but its program no longer changes PLC_HEARTBEAT. One beat
      // first: monitoring starts with the first change (a daemon just restarted has seen none).
      if (plc_ && plc_->set_heartbeat(true) && plc_->set_heartbeat(false)) {
        const auto until =
            Clock::now() + std::chrono::duration<double>(settings_.plc_heartbeat_timeout_s + 5.0);
        (void)plc_->wait_for(
            [until](const auto& s) { return s.bit(regs::kDiPlcCommLost) || Clock::now() > until; },
            "PLC_COMM_LOST");
        std::this_thread::sleep_for(std::chrono::duration<double>(uniform(0.0, 0.5)));
        if (!plc_->set_heartbeat(true)) drop_connection();
      }
      break;
    case FaultKind::kKill:
      idle(uniform(0.0, busy_s + 0.3));  // scanning, analysing, writing, or done
      station_.kill_and_restart();
      drop_connection();  // its connection died with the daemon
      break;
    default:
      break;
  }
}

void Campaign::repair_after(FaultKind kind) {
  if (kind != FaultKind::kUnplug && kind != FaultKind::kStuckHalt) return;
  // The operator: the cable goes back in; a stalled endpoint is power-cycled, as ERROR_DETAIL 5
  // tells (docs/modbus-register-map.md).
  if (kind == FaultKind::kStuckHalt) emulator_.unplug();
  idle(uniform(0.05, 0.5));
  emulator_.plug();
  // The cycle ends when the station has the scanner back (its runner probes once a second).
  if (plc_ && !plc_->wait_for([](const auto& s) { return s.bit(regs::kDiScannerOnline); },
                              "SCANNER_ONLINE"))
    drop_connection();
}

void Campaign::sample_usage() {
  // With the scanner open, so that a daemon just restarted is compared with itself later on.
  if (!plc_) return;
  auto status = plc_->read_status();
  if (!status || !status->bit(regs::kDiScannerOnline)) return;
  const pid_t pid = station_.pid();
  const Usage u = usage_of(pid);
  if (tally_.first.fds == 0) tally_.first = u;
  tally_.peak.rss_kb = std::max(tally_.peak.rss_kb, u.rss_kb);
  tally_.peak.fds = std::max(tally_.peak.fds, u.fds);
  tally_.last = u;
  Life& life = lives_.emplace(pid, Life{u, 0}).first->second;
  ++life.cycles;
  tally_.fd_growth_in_one_life = std::max(tally_.fd_growth_in_one_life, u.fds - life.first.fds);
  if (life.cycles >= tally_.longest_life_cycles) {
    tally_.longest_life_cycles = life.cycles;
    tally_.longest_life_first = life.first;
    tally_.longest_life_last = u;
  }
}

namespace {

void write_config(const CampaignSettings& s, const CampaignPaths& p) {
  std::ofstream(p.config) << "modbus { bind_address: \"127.0.0.1\" port: 0\n"
                          << "  plc_heartbeat_timeout_s: " << s.plc_heartbeat_timeout_s << " }\n"
                          << "scanner { kind: LASER_LINE timeout_s: " << s.scanner_timeout_s
                          << " }\n"
                             "parts { part_id: 1 cad_file: \""
                          << springscan::test_paths::source("demo/hat-profile.step")
                          << "\"\n  settings { verdict { tolerance_mm: 0.5 "
                             "angle_tolerance_deg: 2.0 } } }\n"
                          << "report_dir: \"" << p.reports << "\"\nmodel_cache_dir: \"" << p.dir
                          << "/cache\"\nreport_retention: 20\nlog_level: \"info\"\n";
}

}  // namespace

int run_fault_campaign(const CampaignSettings& settings) {
  const fs::path dir =
      fs::temp_directory_path() / ("springscan-campaign-" + std::to_string(getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  const CampaignPaths paths{dir.string(), (dir / "station.textproto").string(),
                            (dir / "reports").string(), (dir / "springscand.log").string()};
  auto emulator = make_demo_scanner(settings.surface_points, settings.step_mm,
                                    settings.points_per_profile, settings.scan_s);
  if (!emulator) return 1;
  write_config(settings, paths);
  SupervisorSettings supervised{springscan::test_paths::kSpringscand,
                                paths.config,
                                paths.dir,
                                paths.log,
                                {"LD_PRELOAD=" + simulators::umockdev_preload_library(),
                                 "UMOCKDEV_DIR=" + emulator->root_dir()}};
  supervised.restart_delay_s = settings.restart_delay_s;
  int result = 1;
  {
    Supervisor station(supervised);
    Campaign campaign(settings, paths, *emulator, station);
    const auto start = Clock::now();
    const bool finished = campaign.run();
    const double wall_s = std::chrono::duration<double>(Clock::now() - start).count();
    const int stop_status = station.stop();
    print_campaign(settings, campaign.tally(), station, wall_s, stop_status);
    const bool clean =
        finished && campaign.tally().failures() == 0 && station.crashes() == 0 && stop_status == 0;
    result = clean ? 0 : 1;
    if (!clean) std::fprintf(stderr, "springscand's log: %s (kept)\n", paths.log.c_str());
  }
  if (result == 0 && !settings.keep_files) fs::remove_all(dir);
  return result;
}

}  // namespace springscan::bench
