#pragma once
// The station: the event loop that ties the Modbus server, the register image, the state
// machine, the job runner and the report store together. One thread runs step() in a loop;
// it never waits on a scan or an analysis (those run on the runner's thread) and it bumps the
// HEARTBEAT register and sends the systemd watchdog from the same iteration (notes section 4).

#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>

#include "analysis/core/expected.hpp"
#include "daemon/job_runner.hpp"
#include "daemon/log.hpp"
#include "daemon/modbus_server.hpp"
#include "daemon/register_image.hpp"
#include "daemon/report_store.hpp"
#include "daemon/state_machine.hpp"
#include "drivers/scanner.hpp"

namespace springscan::daemon {

struct StationSettings {
  ModbusServerSettings modbus;
  regs::WordOrder word_order = regs::WordOrder::kAbcd;
  MachineSettings machine;
  ReportStoreSettings reports;
  RunnerSettings runner;
};

/// Receives sd_notify(3) messages ("READY=1", "STATUS=...", "WATCHDOG=1"). May be empty.
using NotifyFn = std::function<void(const std::string& message)>;
/// Receives the machine status after every update, on the event loop's thread: it must return
/// at once (the operator page copies it, page_feed.hpp).
/// The machine's status and CALIBRATION_DRIFT (the check part's latch, not the machine's).
using StatusFn = std::function<void(const MachineStatus& status, bool calibration_drift)>;

class Station {
 public:
  /// Opens the report store (restoring the last result, RESULT_VALID = 0), binds the Modbus
  /// port and starts the runner. `scanner` and `log` must outlive the station.
  static analysis::Expected<std::unique_ptr<Station>> create(const StationSettings& settings,
                                                             drivers::Scanner& scanner,
                                                             AnalyzeFn analyze, Log& log,
                                                             NotifyFn notify = {});
  ~Station();

  /// The Modbus port actually bound.
  int port() const { return server_->port(); }
  std::uint16_t boot_id() const { return live_.boot_id; }
  /// CALIBRATION_DRIFT: a check part was beyond its references and none has passed since.
  bool calibration_drift() const { return live_.calibration_drift; }
  /// The report store, for readers on other threads (the result publisher).
  const ReportStore& store() const { return store_; }
  /// Sends READY=1 and runs step() until `stop` becomes true.
  void run(const std::atomic<bool>& stop);
  /// One loop iteration: waits at most `max_wait_ms` for sockets or the runner, serves them.
  void step(int max_wait_ms);

  const MachineStatus& status() const { return machine_.status(); }
  /// Sets the status watcher (before run()).
  void watch_status(StatusFn watcher) { watch_status_ = std::move(watcher); }
  const ModbusServerStats& modbus_stats() const { return server_->stats(); }
  std::size_t modbus_connections() const { return server_->connection_count(); }

 private:
  Station(const StationSettings& settings, ReportStore store, Log& log, NotifyFn notify);
  void restore_last_result();
  void handle_runner_events(Clock::time_point now);
  void restore_calibration_drift();
  void on_check_part(const v1::CheckResult& check, std::uint16_t part_id);
  void update_machine(Clock::time_point now);
  void log_event(MachineEvent event, const PlcControl& plc);
  void tick(Clock::time_point now);
  void notify(const std::string& message) const;
  std::string status_text() const;

  StationSettings settings_;
  Log& log_;
  NotifyFn notify_;
  StatusFn watch_status_;
  RegisterImage image_;
  InspectionMachine machine_;
  ReportStore store_;
  std::unique_ptr<JobRunner> runner_;
  std::unique_ptr<ModbusServer> server_;
  LiveValues live_;
  std::uint64_t last_record_ = 0;
  Clock::time_point next_tick_;
  std::string last_status_text_;
  std::string last_result_text_ = "no result yet";
};

}  // namespace springscan::daemon
