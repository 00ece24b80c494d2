#pragma once
// Hardware-in-the-loop harness: springscand as a real child process (STYLE.md section 7: port
// 0, readiness awaited, stopped by pid). The harness plays systemd: it binds a NOTIFY_SOCKET,
// waits for READY=1 and reads the bound Modbus port from the MODBUS_PORT= line the daemon
// sends with it. Optional environment (LD_PRELOAD, UMOCKDEV_DIR) puts the child under the
// emulated USB scanner; an optional output file takes the child's stdout and stderr (appended,
// so a supervisor restarting the daemon keeps one log, as the journal would).

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

extern char** environ;

namespace springscan::daemon::testing {

class DaemonProcess {
 public:
  /// Starts `exe --config config` with `extra_env` ("NAME=value") added; waits for READY=1.
  /// `output_path` (empty: inherited) receives the child's stdout and stderr, appended.
  DaemonProcess(const std::string& exe, const std::string& config, const std::string& work_dir,
                const std::vector<std::string>& extra_env, double ready_timeout_s = 60.0,
                const std::string& output_path = "") {
    notify_path_ = work_dir + "/notify.sock";
    ::unlink(notify_path_.c_str());
    notify_fd_ = ::socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC, 0);
    sockaddr_un addr{};
    addr.sun_family = AF_UNIX;
    notify_path_.copy(addr.sun_path, sizeof addr.sun_path - 1);
    if (::bind(notify_fd_, reinterpret_cast<sockaddr*>(&addr), sizeof addr) != 0) {
      throw std::runtime_error("cannot bind " + notify_path_);
    }
    // This environment, with NOTIFY_SOCKET and `extra_env` replacing same-named entries
    // (getenv returns the first match, so appending would not override).
    std::vector<std::string> added = extra_env;
    added.push_back("NOTIFY_SOCKET=" + notify_path_);
    const auto name_of = [](const std::string& entry) { return entry.substr(0, entry.find('=')); };
    std::vector<std::string> env_strings;
    for (char** e = environ; *e != nullptr; ++e) {
      const std::string entry = *e;
      bool replaced = false;
      for (const auto& a : added) replaced = replaced || name_of(a) == name_of(entry);
      if (!replaced) env_strings.push_back(entry);
    }
    for (const auto& e : added) env_strings.push_back(e);
    std::vector<char*> envp;
    for (auto& e : env_strings) envp.push_back(e.data());
    envp.push_back(nullptr);
    std::string exe_copy = exe, flag = "--config", config_copy = config;
    char* argv[] = {exe_copy.data(), flag.data(), config_copy.data(), nullptr};
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    if (!output_path.empty()) {
      posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, output_path.c_str(),
                                       O_WRONLY | O_CREAT | O_APPEND, 0644);
      posix_spawn_file_actions_adddup2(&actions, STDOUT_FILENO, STDERR_FILENO);
    }
    const int spawned = posix_spawn(&pid_, exe.c_str(), &actions, nullptr, argv, envp.data());
    posix_spawn_file_actions_destroy(&actions);
    if (spawned != 0) throw std::runtime_error("cannot start " + exe);
    try {
      wait_ready(ready_timeout_s);
    } catch (...) {
      ::close(notify_fd_);
      throw;
    }
    drain_ = std::thread([this] { drain_notifications(); });
  }
  ~DaemonProcess() {
    if (pid_ > 0) stop(SIGTERM);
    stop_drain_ = true;
    drain_.join();
    ::close(notify_fd_);
    ::unlink(notify_path_.c_str());
  }
  DaemonProcess(const DaemonProcess&) = delete;
  DaemonProcess& operator=(const DaemonProcess&) = delete;

  int port() const { return port_; }
  /// True once the daemon sent a notification containing `text` after READY=1.
  bool notified(const std::string& text) {
    std::lock_guard lock(mutex_);
    return notes_.find(text) != std::string::npos;
  }
  /// The value of the last "NAME=value" line the daemon sent before READY=1 (HTTP_PORT=), or "".
  std::string early_value(const std::string& name) const {
    const std::size_t at = early_notes_.rfind(name + "=");
    if (at == std::string::npos) return "";
    const std::size_t start = at + name.size() + 1;
    return early_notes_.substr(start, early_notes_.find('\n', start) - start);
  }
  pid_t pid() const { return pid_; }
  /// The wait status if the child has exited by itself (reaped now; pid() is then -1), else
  /// nullopt. Never blocks: a supervisor polls it to tell a crash from a running daemon.
  std::optional<int> exited() {
    int status = 0;
    if (pid_ <= 0 || ::waitpid(pid_, &status, WNOHANG) != pid_) return std::nullopt;
    pid_ = -1;
    return status;
  }
  /// Sends `signal` and reaps the child; returns its wait status.
  /// A child that has not exited 10 s after `signal` is killed (SIGKILL), as systemd does
  /// after TimeoutStopSec.
  int stop(int signal) {
    int status = 0;
    if (pid_ <= 0) return status;  // already reaped: kill(-1, ...) would signal everything
    ::kill(pid_, signal);
    for (int i = 0; i < 1000; ++i) {
      if (::waitpid(pid_, &status, WNOHANG) == pid_) {
        pid_ = -1;
        return status;
      }
      ::usleep(10000);
    }
    ::kill(pid_, SIGKILL);
    ::waitpid(pid_, &status, 0);
    pid_ = -1;
    return status;
  }

 private:
  void wait_ready(double timeout_s) {
    const auto deadline = std::chrono::steady_clock::now() +
                          std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                              std::chrono::duration<double>(timeout_s));
    while (std::chrono::steady_clock::now() < deadline) {
      timeval tv{0, 200000};
      setsockopt(notify_fd_, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
      char buffer[4096];
      const ssize_t n = ::recv(notify_fd_, buffer, sizeof buffer - 1, 0);
      if (n > 0) {
        const std::string message(buffer, static_cast<std::size_t>(n));
        early_notes_.append(message).push_back('\n');
        const auto at = message.find("MODBUS_PORT=");
        if (message.find("READY=1") != std::string::npos && at != std::string::npos) {
          port_ = std::stoi(message.substr(at + 12));
          return;
        }
      }
      int status = 0;
      if (::waitpid(pid_, &status, WNOHANG) == pid_) {
        pid_ = -1;
        throw std::runtime_error("springscand exited before READY (status " +
                                 std::to_string(status) + ")");
      }
    }
    throw std::runtime_error("springscand did not send READY=1 in time");
  }

  void drain_notifications() {
    while (!stop_drain_) {
      char buffer[4096];
      const ssize_t n = ::recv(notify_fd_, buffer, sizeof buffer, 0);  // SO_RCVTIMEO 200 ms
      if (n > 0) {
        std::lock_guard lock(mutex_);
        notes_.append(buffer, static_cast<std::size_t>(n)).push_back('\n');
        if (notes_.size() > 65536) notes_.erase(0, notes_.size() - 65536);
      }
    }
  }

  std::string notify_path_;
  int notify_fd_ = -1;
  pid_t pid_ = -1;
  int port_ = 0;
  std::thread drain_;
  std::atomic<bool> stop_drain_{false};
  std::mutex mutex_;
  std::string notes_;        // the notifications after READY=1 (the last 64 KiB)
  std::string early_notes_;  // the notifications up to READY=1 (written before drain_ starts)
};

}  // namespace springscan::daemon::testing
