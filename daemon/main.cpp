// springscand: the station daemon (DESIGN.md "The daemon"). The composition root: load the
// config, build the scanner and the analysis, run the station until SIGTERM.
//   springscand --config FILE [--check] | --help | --version
#include <signal.h>
#include <systemd/sd-daemon.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cstring>
#include <memory>
#include <optional>
#include <string>
#include <thread>

#include "analysis/cad/model.hpp"
#include "analysis/messages/cad_model_proto.hpp"
#include "daemon/config.hpp"
#include "daemon/page_server.hpp"
#include "daemon/result_publisher.hpp"
#include "daemon/station.hpp"
#include "daemon/wiring.hpp"
#include "drivers/scanner_proto.hpp"

namespace {

std::atomic<bool> g_stop{false};

// After SIGTERM a running scan is cancelled within about 0.1 s (the driver asks the runner
// between transfers); an analysis cannot be interrupted, so shutdown waits for it at most this
// long and then exits without its result. That is safe: a report is written to a temporary
// and renamed, and RESULT_VALID is only ever set after that (the kill -9 case). Below the
// unit's TimeoutStopSec=10s, so systemd never has to SIGKILL.
constexpr auto kStopBound = std::chrono::seconds(5);

void on_signal(int) { g_stop = true; }

void install_signal_handlers() {
  struct sigaction action {};
  action.sa_handler = on_signal;
  sigemptyset(&action.sa_mask);
  action.sa_flags = 0;  // no SA_RESTART: poll() returns EINTR and the loop sees the flag
  sigaction(SIGTERM, &action, nullptr);
  sigaction(SIGINT, &action, nullptr);
  signal(SIGPIPE, SIG_IGN);
}

constexpr const char* kUsage =
    "usage: springscand --config FILE [--check]\n"
    "       springscand --help | --version\n"
    "  --config FILE  the station config (protobuf text format; see the commented\n"
    "                 /etc/springscan/springscand.textproto)\n"
    "  --check        validate the config and exit: 0 when it is usable, 2 with the first\n"
    "                 problem (file:line) otherwise\n"
    "Runs the inspection station: Modbus TCP for the PLC, the USB scanner, the analysis.\n"
    "Exit codes: 0 clean stop, 1 could not start or stop was forced, 2 bad usage or config.\n";

int usage(const std::string& message) {
  std::fprintf(stderr, "springscand: %s\n%s", message.c_str(), kUsage);
  return 2;
}

// --check: every part's CAD file loads and segments, as the first trigger of that part would
// need (its settings were validated with the config).
bool check_part_models(const std::vector<springscan::daemon::PartEntry>& parts,
                       springscan::daemon::Log& log) {
  namespace analysis = springscan::analysis;
  for (const auto& part : parts) {
    const std::string name = "part " + std::to_string(part.part_id) + " (" + part.name + ")";
    auto model_settings = analysis::from_proto(part.settings.cad_model());
    auto model = model_settings ? analysis::load_part_model(part.cad_file, *model_settings)
                                : analysis::Expected<analysis::PartModel>(model_settings.error());
    if (!model) {
      log.error(name + ": " + model.message());
      return false;
    }
    log.info(name + ": " + part.cad_file + " loads: " + std::to_string(model->face_count) +
             " faces, " + std::to_string(model->segmentation.flanges.size()) + " flanges, " +
             std::to_string(model->segmentation.bends.size()) + " bends");
  }
  return true;
}

// The command line: what to do, or the exit status to return at once (--help, bad usage).
struct CommandLine {
  std::string config_path;
  bool check_only = false;
  std::optional<int> exit_now;
};

CommandLine parse_command_line(int argc, char** argv) {
  CommandLine cl;
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--config") == 0 && i + 1 < argc) {
      cl.config_path = argv[++i];
    } else if (std::strcmp(argv[i], "--check") == 0) {
      cl.check_only = true;
    } else if (std::strcmp(argv[i], "--help") == 0 || std::strcmp(argv[i], "-h") == 0) {
      std::fputs(kUsage, stdout);
      cl.exit_now = 0;
      return cl;
    } else if (std::strcmp(argv[i], "--version") == 0) {
      std::printf("springscand %s\n", SPRINGSCAN_VERSION);
      cl.exit_now = 0;
      return cl;
    } else {
      cl.exit_now = usage(std::string("unknown argument ") + argv[i]);
      return cl;
    }
  }
  if (cl.config_path.empty()) cl.exit_now = usage("--config FILE is required");
  return cl;
}

// --check: the head calibration in force, with its date, and the check part that watches it
// (docs/calibration.md), so a technician sees which calibration a config brings.
void log_calibration(const springscan::daemon::DaemonSettings& settings,
                     springscan::daemon::Log& log) {
  const springscan::v1::ScannerConfig& scanner = settings.scanner;
  if (scanner.has_calibration()) {
    const springscan::v1::StationCalibration& c = scanner.calibration();
    std::string heads;
    for (const auto& head : c.heads()) heads += (heads.empty() ? "" : ", ") + head.name();
    log.info("calibration in force: made " +
             (c.created_utc().empty() ? "(no date)" : c.created_utc()) +
             " by springscan calibrate from artefact " + c.artefact_file() + ", " +
             std::to_string(c.heads_size()) + " head(s)" + (heads.empty() ? "" : ": " + heads));
  } else {
    log.info(std::string("calibration in force: ") +
             (scanner.has_laser_calibration() ? "scanner.laser_calibration as typed into the config"
                                              : "the scanner's default mount") +
             ", no record of springscan calibrate (no date)");
  }
  const auto& check = settings.station.runner.check_part;
  log.info(check ? "check part: part " + std::to_string(check->part_id()) + ", " +
                       std::to_string(check->reference_size()) +
                       " reference(s); beyond a limit raises CALIBRATION_DRIFT"
                 : std::string("no check part (check_part { }): calibration drift is not watched"));
}

// --check with a GenICam profiler: it must answer and have every feature the driver uses (a
// USB head is only looked for when the station runs: it may be plugged in later).
bool check_genicam_camera(const springscan::v1::ScannerConfig& config,
                          springscan::daemon::Log& log) {
  if (!config.has_genicam()) return true;
  auto scanner = springscan::drivers::make_scanner(config);
  if (!scanner) {
    log.error("scanner: " + scanner.message());
    return false;
  }
  const auto info = (*scanner)->identify();
  if (!info) {
    log.error("scanner: " + info.message());
    return false;
  }
  log.info("scanner: GenICam camera " + info->model + " serial " + info->serial +
           " has every feature the driver uses");
  return true;
}

// --check: the config was valid; every CAD file must load too. Exit status 0 or 2.
int check_config(const std::string& config_path, const springscan::daemon::DaemonSettings& settings,
                 springscan::daemon::Log& log) {
  log_calibration(settings, log);
  if (!check_part_models(settings.parts, log)) return 2;
  if (!check_genicam_camera(settings.scanner, log)) return 2;
  const springscan::daemon::MqttSettings& mqtt = settings.mqtt;
  log.info(config_path + ": config OK" +
           (mqtt.enabled ? "; results published to MQTT broker " + mqtt.host + ":" +
                               std::to_string(mqtt.port) + (mqtt.ca_file.empty() ? "" : " (TLS)") +
                               " as station " + mqtt.station
                         : "; MQTT publishing off"));
  const springscan::daemon::PageSettings& http = settings.http;
  log.info(http.enabled ? "operator page on http://" + http.address + ":" +
                              std::to_string(http.port) + "/ (docs/operator-page.md)"
                        : "operator page off (no http { } section)");
  return 0;
}

// The operator page (docs/operator-page.md), when configured: fed by the station's status and
// the report store; HTTP_PORT= tells a supervisor the port bound (port 0 takes a free one).
springscan::analysis::Expected<std::unique_ptr<springscan::daemon::PageServer>> start_page(
    const springscan::daemon::DaemonSettings& settings, springscan::daemon::Station& station,
    springscan::daemon::Log& log) {
  using namespace springscan::daemon;
  if (!settings.http.enabled) return std::unique_ptr<PageServer>();
  auto page =
      PageServer::start(settings.http, station.store(), settings.station.runner.station_name, log);
  if (!page) return page.error();
  PageFeed& feed = (*page)->feed();
  station.watch_status([&feed](const MachineStatus& status, bool calibration_drift) {
    feed.on_status(status, calibration_drift);
  });
  log.info("operator page on http://" + settings.http.address + ":" +
           std::to_string((*page)->port()) + "/");
  sd_notify(0, ("HTTP_PORT=" + std::to_string((*page)->port())).c_str());
  return page;
}

// After the station stopped: a watchdog bounds the wait for a running analysis (kStopBound).
void arm_forced_stop(springscan::daemon::Log& log) {
  std::thread([&log] {
    std::this_thread::sleep_for(kStopBound);
    // Non-zero, so systemd (and a technician reading `systemctl status`) can tell a forced
    // stop from a clean one.
    log.error("shutdown forced: the analysis still ran after " +
              std::to_string(kStopBound.count()) +
              " s; exiting with status 1 without its result (nothing was reported to the PLC)");
    _exit(1);
  }).detach();
}

// The service: scanner, station and publisher from the settings, run until SIGTERM.
int run_station(const springscan::daemon::DaemonSettings& settings, springscan::daemon::Log& log) {
  using namespace springscan::daemon;
  const MosquittoLibrary mosquitto_library;
  install_signal_handlers();
  // The one way from the config to a driver (drivers/scanner_proto.hpp), calibration included.
  auto scanner = springscan::drivers::make_scanner(settings.scanner);
  if (!scanner) {
    log.error("invalid config: " + scanner.message());
    return 2;
  }
  const bool tactile = settings.scanner.kind() == springscan::v1::ScannerConfig::TACTILE_PROBE;
  log.info(std::string("scanner: ") + (tactile ? "tactile probe" : "laser line") +
           (settings.scanner.serial().empty() ? "" : " serial " + settings.scanner.serial()));
  auto station = Station::create(settings.station, **scanner,
                                 make_analysis(settings.parts, settings.model_cache_dir, log), log,
                                 [](const std::string& message) { sd_notify(0, message.c_str()); });
  if (!station) {
    log.error("cannot start: " + station.message());
    sd_notify(0, ("STATUS=cannot start: " + station.message()).c_str());
    return 1;
  }
  // Results to the plant: the publisher reads the report store on its own thread.
  std::unique_ptr<ResultPublisher> publisher;
  if (settings.mqtt.enabled) {
    auto started =
        ResultPublisher::start(settings.mqtt, (*station)->store(), (*station)->boot_id(), log);
    if (!started) {
      log.error("cannot start: " + started.message());
      return 1;
    }
    publisher = std::move(*started);
  }
  auto page = start_page(settings, **station, log);
  if (!page) {
    log.error("cannot start: " + page.message());
    return 1;
  }
  (*station)->run(g_stop);
  arm_forced_stop(log);
  (*station)->watch_status({});  // the loop has stopped; the feed goes next
  page->reset();                 // every open page's stream ends
  publisher.reset();             // "offline" to the broker, the last acknowledged record saved
  station->reset();              // cancels a running scan, waits for the runner
  log.info("springscand stopped");
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  using namespace springscan::daemon;
  const CommandLine cl = parse_command_line(argc, argv);
  if (cl.exit_now) return *cl.exit_now;
  Log log = Log::to_stderr(LogLevel::kInfo);
  auto settings = load_daemon_config(cl.config_path);
  if (!settings) {
    log.error("invalid config: " + settings.message());
    return 2;
  }
  log.set_level(settings->log_level);
  if (cl.check_only) return check_config(cl.config_path, *settings, log);
  return run_station(*settings, log);
}
