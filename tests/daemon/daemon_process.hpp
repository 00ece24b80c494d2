#pragma once
// Hardware-in-the-loop harness: springscand as a real child process (STYLE.md section 7: port
// 0, readiness awaited, stopped by pid). The harness plays systemd: it binds a NOTIFY_SOCKET,
// waits for READY=1 and reads the bound Modbus port from the MODBUS_PORT= line the daemon
// sends with it. Optional environment (LD_PRELOAD, UMOCKDEV_DIR) puts the child under the
// emulated USB scanner.

#include <signal.h>
#include <spawn.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <stdexcept>
#include <string>
#include <vector>

extern char** environ;

namespace springscan::daemon::testing {

class DaemonProcess {
 public:
  /// Starts `exe --config config` with `extra_env` ("NAME=value") added; waits for READY=1.
  DaemonProcess(const std::string& exe, const std::string& config, const std::string& work_dir,
                const std::vector<std::string>& extra_env, double ready_timeout_s = 60.0) {
    notify_path_ = work_dir + "/notify.sock";
    ::unlink(notify_path_.c_str());
    notify_fd_ = ::socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC, 0);
    sockaddr_un addr{};
    addr.sun_family = AF_UNIX;
    notify_path_.copy(addr.sun_path, sizeof addr.sun_path - 1);
    if (::bind(notify_fd_, reinterpret_cast<sockaddr*>(&addr), sizeof addr) != 0) {
      throw std::runtime_error("cannot bind " + notify_path_);
    }
    std::vector<std::string> env_strings;
    for (char** e = environ; *e != nullptr; ++e) {
      const std::string entry = *e;
      if (entry.rfind("NOTIFY_SOCKET=", 0) != 0) env_strings.push_back(entry);
    }
    env_strings.push_back("NOTIFY_SOCKET=" + notify_path_);
    for (const auto& e : extra_env) env_strings.push_back(e);
    std::vector<char*> envp;
    for (auto& e : env_strings) envp.push_back(e.data());
    envp.push_back(nullptr);
    std::string exe_copy = exe, flag = "--config", config_copy = config;
    char* argv[] = {exe_copy.data(), flag.data(), config_copy.data(), nullptr};
    if (posix_spawn(&pid_, exe.c_str(), nullptr, nullptr, argv, envp.data()) != 0) {
      throw std::runtime_error("cannot start " + exe);
    }
    wait_ready(ready_timeout_s);
  }
  ~DaemonProcess() {
    if (pid_ > 0) stop(SIGTERM);
    ::close(notify_fd_);
    ::unlink(notify_path_.c_str());
  }
  DaemonProcess(const DaemonProcess&) = delete;
  DaemonProcess& operator=(const DaemonProcess&) = delete;

  int port() const { return port_; }
  pid_t pid() const { return pid_; }
  /// Sends `signal` and reaps the child; returns its wait status.
  /// A child that has not exited 10 s after `signal` is killed (SIGKILL), as systemd does
  /// after TimeoutStopSec.
  int stop(int signal) {
    int status = 0;
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
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration_cast<
        std::chrono::steady_clock::duration>(std::chrono::duration<double>(timeout_s));
    while (std::chrono::steady_clock::now() < deadline) {
      timeval tv{0, 200000};
      setsockopt(notify_fd_, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
      char buffer[4096];
      const ssize_t n = ::recv(notify_fd_, buffer, sizeof buffer - 1, 0);
      if (n > 0) {
        const std::string message(buffer, static_cast<std::size_t>(n));
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

  std::string notify_path_;
  int notify_fd_ = -1;
  pid_t pid_ = -1;
  int port_ = 0;
};

}  // namespace springscan::daemon::testing
