#include "daemon/station.hpp"

#include <poll.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <random>

#include "analysis/io/file_io.hpp"

namespace springscan::daemon {

namespace {

constexpr auto kTick = std::chrono::milliseconds(100);  // HEARTBEAT period (register map)
constexpr int kWatchdogEveryTicks = 10;                 // WATCHDOG=1 once a second

const char* reject_text(regs::RejectCode code) {
  switch (code) {
    case regs::RejectCode::kBusy:
      return "busy with the previous part: wait for BUSY = 0";
    case regs::RejectCode::kNotEnabled:
      return "TRIGGER_ENABLE (coil 0) is off";
    case regs::RejectCode::kErrorActive:
      return "an error is active: set ERROR_RESET (coil 3)";
    case regs::RejectCode::kResultNotAcked:
      return "the previous result was not acknowledged: set RESULT_ACK (coil 2)";
    case regs::RejectCode::kScannerOffline:
      return "the scanner is offline: check its USB cable";
    case regs::RejectCode::kUnknownPart:
      return "PART_ID is not in the part catalogue of the config";
    case regs::RejectCode::kCommLost:
      return "PLC heartbeat was lost: keep PLC_HEARTBEAT changing, then set ERROR_RESET";
    default:
      return "no reason";
  }
}

const char* state_name(regs::State state) {
  switch (state) {
    case regs::State::kStopped:
      return "STOPPED";
    case regs::State::kIdle:
      return "IDLE";
    case regs::State::kAcquiring:
      return "ACQUIRING";
    case regs::State::kAnalyzing:
      return "ANALYZING";
    case regs::State::kDone:
      return "DONE";
    case regs::State::kFault:
      return "FAULT";
  }
  return "?";
}

/// A random BOOT_ID, never 0 and never the previous start's (kept in <report_dir>/boot_id),
/// so a PLC comparing it always notices a restart.
std::uint16_t next_boot_id(const std::string& report_dir, Log& log) {
  const std::string path = report_dir + "/boot_id";
  int previous = 0;
  if (std::FILE* f = std::fopen(path.c_str(), "r")) {
    if (std::fscanf(f, "%d", &previous) != 1) previous = 0;
    std::fclose(f);
  }
  std::random_device device;
  std::uniform_int_distribution<int> pick(1, 65535);
  int id = pick(device);
  while (id == previous) id = pick(device);
  auto written = analysis::write_file_atomically(path, std::to_string(id) + "\n");
  if (!written) log.warning("cannot record BOOT_ID: " + written.message());
  return static_cast<std::uint16_t>(id);
}

/// Present while CALIBRATION_DRIFT is latched, so that a restart does not clear the alarm.
std::string drift_marker(const std::string& report_dir) {
  return report_dir + "/calibration_drift";
}

}  // namespace

Station::Station(const StationSettings& settings, ReportStore store, Log& log, NotifyFn notify)
    : settings_(settings),
      log_(log),
      notify_(std::move(notify)),
      image_(settings.word_order),
      machine_(settings.machine, Clock::now()),
      store_(std::move(store)),
      next_tick_(Clock::now() + kTick) {
  live_.boot_id = next_boot_id(settings.reports.directory, log);
}

Station::~Station() {
  // The runner goes first: it cancels a running scan and joins before the store is destroyed.
  runner_.reset();
}

analysis::Expected<std::unique_ptr<Station>> Station::create(const StationSettings& settings,
                                                             drivers::Scanner& scanner,
                                                             AnalyzeFn analyze, Log& log,
                                                             NotifyFn notify) {
  auto store = ReportStore::open(settings.reports);
  if (!store) return store.error();
  std::unique_ptr<Station> station(
      new Station(settings, std::move(*store), log, std::move(notify)));
  station->restore_last_result();
  station->restore_calibration_drift();
  auto server = ModbusServer::open(settings.modbus, station->image_.mapping(), log);
  if (!server) return server.error();
  station->server_ = std::move(*server);
  station->runner_ = std::make_unique<JobRunner>(scanner, std::move(analyze), station->store_, log,
                                                 settings.runner);
  station->update_machine(Clock::now());
  return station;
}

void Station::restore_last_result() {
  last_record_ = store_.last_record();
  auto latest = store_.load_latest();
  if (!latest) {
    log_.warning("the last report cannot be read (" + latest.message() +
                 "); the result block starts empty (RESULT_CODE 2, no data)");
    return;
  }
  if (!latest->has_value()) {
    log_.info("no earlier result in " + settings_.reports.directory);
    return;
  }
  // Shown for reference with RESULT_VALID = 0 under a new BOOT_ID: never mistaken for new.
  image_.publish_result(result_block_from_report(**latest));
  last_result_text_ =
      "last result seq " + std::to_string((*latest)->result_seq()) + " from before the restart";
  log_.info("restored the result block of record " + std::to_string(last_record_) + " (seq " +
            std::to_string((*latest)->result_seq()) +
            ") from before the restart; RESULT_VALID stays 0 until the next inspection");
}

void Station::restore_calibration_drift() {
  std::error_code ec;
  if (!std::filesystem::exists(drift_marker(settings_.reports.directory), ec)) return;
  live_.calibration_drift = true;
  log_.warning(
      "CALIBRATION_DRIFT (discrete input 11) is still set from before the restart: the "
      "last check part was beyond its references. Recalibrate the heads, then measure "
      "the check part again (docs/calibration.md)");
}

// The latch: raised by a check part beyond a limit, cleared only by one within all of them.
void Station::on_check_part(const v1::CheckResult& check, std::uint16_t part_id) {
  const bool was = live_.calibration_drift;
  live_.calibration_drift = check.drift();
  const std::string marker = drift_marker(settings_.reports.directory);
  const std::string part = "the check part (part " + std::to_string(part_id) + ")";
  if (check.drift()) {
    auto written = analysis::write_file_atomically(marker, "check part beyond its references\n");
    if (!written) log_.warning("cannot record CALIBRATION_DRIFT: " + written.message());
    log_.error("CALIBRATION DRIFT: " + part + (was ? " is still" : " is") +
               " beyond its references (see the line above and its report). CALIBRATION_DRIFT "
               "(discrete input 11) stays set until a check part passes; the PLC holds "
               "production. Recalibrate the heads (springscan calibrate, docs/calibration.md), "
               "then measure the check part again.");
    return;
  }
  std::error_code ec;
  std::filesystem::remove(marker, ec);
  if (was)
    log_.info(part +
              " is within its references again: CALIBRATION_DRIFT cleared, production "
              "may resume");
}

void Station::run(const std::atomic<bool>& stop) {
  log_.info("springscand ready: Modbus TCP on " + settings_.modbus.bind_address + ":" +
            std::to_string(port()) + ", unit id " + std::to_string(settings_.modbus.unit_id) +
            ", boot id " + std::to_string(live_.boot_id));
  notify("READY=1\nSTATUS=" + status_text() + "\nMODBUS_PORT=" + std::to_string(port()));
  while (!stop.load()) step(100);
  notify("STOPPING=1");
}

void Station::step(int max_wait_ms) {
  std::vector<pollfd> fds;
  server_->add_poll_fds(fds);
  fds.push_back(pollfd{runner_->wake_fd(), POLLIN, 0});
  const auto before = Clock::now();
  const int until_tick = static_cast<int>(std::max<long long>(
      0, std::chrono::duration_cast<std::chrono::milliseconds>(next_tick_ - before).count() + 1));
  const int timeout = server_->expire(before, std::min(max_wait_ms, until_tick));
  const int ready = poll(fds.data(), fds.size(), timeout);
  const auto now = Clock::now();
  if (ready > 0 && (fds.back().revents & POLLIN) != 0) handle_runner_events(now);
  if (ready >= 0) {
    server_->service(fds, now, [this] { update_machine(Clock::now()); });
  }
  tick(now);
  update_machine(now);
}

void Station::handle_runner_events(Clock::time_point now) {
  for (RunnerEvent& event : runner_->take_events()) {
    if (event.kind == RunnerEvent::Kind::kAcquired) {
      machine_.on_acquired();
      continue;
    }
    if (event.end.persisted) {
      // Data and RESULT_SEQ first, then the bits: one thread, so no read sees half of it.
      image_.publish_result(event.block);
      if (event.check) on_check_part(*event.check, event.block.part_id);
      last_result_text_ =
          "last result seq " + std::to_string(event.block.seq) + " part " +
          std::to_string(event.block.part_id) + ": " +
          (event.end.result_code == regs::ResultCode::kOk ? "PASS"
           : event.end.result_code == regs::ResultCode::kUndecided
               ? "UNDECIDED"
               : "FAIL/code " + std::to_string(static_cast<int>(event.end.result_code)));
    }
    machine_.on_job_finished(event.end, now);
  }
}

void Station::update_machine(Clock::time_point now) {
  const PlcControl plc = image_.plc_control();
  const MachineStep step = machine_.update(plc, runner_->scanner_online(), now);
  for (MachineEvent event : step.events) log_event(event, plc);
  if (step.start) runner_->start(RunnerJob{++last_record_, *step.start});
  live_.scan_progress_pct = machine_.status().busy ? runner_->progress_pct() : 0;
  image_.publish_status(machine_.status(), live_);
  image_.refresh_window();
  if (watch_status_) watch_status_(machine_.status(), live_.calibration_drift);
  const std::string text = status_text();
  if (text != last_status_text_) {
    notify("STATUS=" + text);
    last_status_text_ = text;
  }
}

void Station::log_event(MachineEvent event, const PlcControl& plc) {
  const MachineStatus& s = machine_.status();
  const std::string ids =
      "job " + std::to_string(plc.job_id) + " part " + std::to_string(plc.part_id);
  switch (event) {
    case MachineEvent::kTriggerAccepted:
      log_.info("trigger accepted: " + ids + " (trigger #" + std::to_string(s.trigger_count) + ")");
      break;
    case MachineEvent::kTriggerRejected:
      log_.warning("trigger REFUSED for " + ids + " (REJECT_CODE " +
                   std::to_string(static_cast<int>(s.reject_code)) +
                   "): " + reject_text(s.reject_code));
      break;
    case MachineEvent::kTriggerHeldAtStart:
      log_.warning("TRIGGER is already high at start: ignored until the PLC drops it");
      break;
    case MachineEvent::kTriggerNotReleased:
      log_.error("the PLC did not drop TRIGGER within " +
                 std::to_string(settings_.machine.trigger_release_timeout_s) +
                 " s after TRIG_ACK (ERROR_CODE 6). Check the PLC program's handshake, then "
                 "set ERROR_RESET (coil 3).");
      break;
    case MachineEvent::kResultAcked:
      log_.debug("result acknowledged by the PLC");
      break;
    case MachineEvent::kResultStale:
      log_.warning("the PLC did not acknowledge the result within " +
                   std::to_string(settings_.machine.result_ttl_s) +
                   " s (modbus.result_ttl_s): RESULT_STALE = 1; the result stays valid until "
                   "RESULT_ACK or the next accepted trigger, its report is on disk");
      break;
    case MachineEvent::kResultClearedByJobChange:
      log_.info("JOB_ID changed to " + std::to_string(plc.job_id) +
                " before the result was acknowledged: RESULT_VALID dropped");
      break;
    case MachineEvent::kErrorReset:
      log_.info(s.result_valid ? "ERROR_RESET from the PLC: errors cleared; the result stays valid "
                                 "until RESULT_ACK"
                               : "ERROR_RESET from the PLC: errors cleared");
      break;
    case MachineEvent::kCommLost:
      log_.error("PLC heartbeat lost: PLC_HEARTBEAT (holding 3) unchanged for " +
                 std::to_string(settings_.machine.plc_heartbeat_timeout_s) +
                 " s (ERROR_CODE 7 unless another error is latched). READY is off; a result "
                 "stays valid. Check the PLC and the network, then set ERROR_RESET.");
      break;
    case MachineEvent::kCommRestored:
      log_.info("PLC heartbeat is back");
      break;
  }
}

void Station::tick(Clock::time_point now) {
  while (now >= next_tick_) {
    next_tick_ += kTick;
    ++live_.heartbeat;
    // WATCHDOG=1 from the iteration that bumps HEARTBEAT: a stuck loop stops both.
    if (live_.heartbeat % kWatchdogEveryTicks == 0) notify("WATCHDOG=1");
  }
}

void Station::notify(const std::string& message) const {
  if (notify_) notify_(message);
}

std::string Station::status_text() const {
  const MachineStatus& s = machine_.status();
  std::string text = state_name(s.state);
  text += s.ready ? ", ready" : ", not ready";
  if (s.error()) text += ", ERROR " + std::to_string(static_cast<int>(s.error_code));
  if (!s.scanner_online) text += ", scanner offline";
  if (s.plc_comm_lost) text += ", PLC comm lost";
  if (s.result_stale) text += ", result not collected";
  if (live_.calibration_drift) text += ", CALIBRATION DRIFT";
  return text + "; " + last_result_text_;
}

}  // namespace springscan::daemon
