#include "bench/soak_supervisor.hpp"

#include <csignal>
#include <cstring>
#include <stdexcept>
#include <thread>

namespace springscan::bench {

std::string describe_wait_status(int status) {
  if (WIFEXITED(status)) return "exit " + std::to_string(WEXITSTATUS(status));
  if (WIFSIGNALED(status))
    return "signal " + std::to_string(WTERMSIG(status)) + " (" + strsignal(WTERMSIG(status)) + ")";
  return "wait status " + std::to_string(status);
}

Supervisor::Supervisor(SupervisorSettings settings) : settings_(std::move(settings)) { start(); }

Supervisor::~Supervisor() {
  if (process_ && process_->pid() > 0) process_->stop(SIGTERM);
}

void Supervisor::start() {
  // A daemon that exits before READY is a crash too; systemd would keep trying (with
  // StartLimitBurst), so do we, a few times.
  for (int attempt = 1;; ++attempt) {
    ++starts_;
    try {
      process_ = std::make_unique<daemon::testing::DaemonProcess>(
          settings_.exe, settings_.config, settings_.work_dir, settings_.env,
          settings_.ready_timeout_s, settings_.log_path);
      return;
    } catch (const std::exception& e) {
      process_.reset();
      crash_notes_.push_back(std::string("start ") + std::to_string(starts_) + ": " + e.what());
      if (attempt >= settings_.max_failed_starts)
        throw std::runtime_error("springscand does not start: " + std::string(e.what()));
      std::this_thread::sleep_for(std::chrono::duration<double>(settings_.restart_delay_s));
    }
  }
}

void Supervisor::restart() {
  process_.reset();  // joins the notification thread, frees the notify socket's path
  std::this_thread::sleep_for(std::chrono::duration<double>(settings_.restart_delay_s));
  start();
}

bool Supervisor::check() {
  const auto status = process_->exited();
  if (!status) return false;
  crash_notes_.push_back("springscand (start " + std::to_string(starts_) +
                         ") ended by itself: " + describe_wait_status(*status));
  restart();
  return true;
}

void Supervisor::kill_and_restart() {
  if (check()) return;  // it had already died: that was a crash, and it is restarted
  const int status = process_->stop(SIGKILL);
  ++kills_;
  if (!WIFSIGNALED(status) || WTERMSIG(status) != SIGKILL) {
    // It ended some other way before our signal arrived.
    crash_notes_.push_back("springscand ended before our SIGKILL: " + describe_wait_status(status));
  }
  restart();
}

int Supervisor::stop() {
  if (const auto status = process_->exited()) {
    crash_notes_.push_back("springscand ended by itself before the final stop: " +
                           describe_wait_status(*status));
    return *status;
  }
  return process_->stop(SIGTERM);
}

}  // namespace springscan::bench
