#pragma once
// The fault campaign's stand-in for systemd (config/springscand.service: Restart=always):
// keeps one springscand running, restarts it after it exits, and tells the exits it caused
// (SIGKILL on purpose, SIGTERM at the end) from crashes (an exit nobody asked for: by itself or
// by a signal we did not send). Not thread-safe: the campaign's one thread calls everything.

#include <memory>
#include <string>
#include <vector>

#include "tests/daemon/daemon_process.hpp"

namespace springscan::bench {

struct SupervisorSettings {
  std::string exe;                ///< springscand
  std::string config;             ///< its --config
  std::string work_dir;           ///< for the notify socket
  std::string log_path;           ///< the daemon's stdout and stderr, appended over restarts
  std::vector<std::string> env;   ///< added to the environment ("NAME=value")
  double restart_delay_s = 0.1;   ///< RestartSec (the unit has 1 s; shorter keeps cycles fast)
  double ready_timeout_s = 60.0;  ///< TimeoutStartSec
  int max_failed_starts = 5;      ///< give up after this many starts in a row without READY
};

class Supervisor {
 public:
  /// Starts the daemon; throws std::runtime_error when it never becomes ready.
  explicit Supervisor(SupervisorSettings settings);
  ~Supervisor();
  Supervisor(const Supervisor&) = delete;
  Supervisor& operator=(const Supervisor&) = delete;

  /// The Modbus port of the daemon running now (port 0 in the config: new at every start).
  int port() const { return process_->port(); }
  pid_t pid() const { return process_->pid(); }
  /// True if the daemon had exited by itself (a crash: counted, noted and restarted).
  bool check();
  /// SIGKILL, as a power cut or the OOM killer would, then the restart systemd would do.
  void kill_and_restart();
  /// SIGTERM (systemctl stop); returns the wait status, 0 for a clean stop.
  int stop();

  int crashes() const { return static_cast<int>(crash_notes_.size()); }
  const std::vector<std::string>& crash_notes() const { return crash_notes_; }
  int kills() const { return kills_; }
  int starts() const { return starts_; }

 private:
  void restart();
  void start();

  SupervisorSettings settings_;
  std::unique_ptr<daemon::testing::DaemonProcess> process_;
  std::vector<std::string> crash_notes_;
  int kills_ = 0;
  int starts_ = 0;
};

/// "exit 1" or "signal 11 (Segmentation fault)" for a wait status.
std::string describe_wait_status(int status);

}  // namespace springscan::bench
