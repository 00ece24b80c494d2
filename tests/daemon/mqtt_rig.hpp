#pragma once
// MQTT test peers (STYLE.md section 7: loopback, readiness awaited, stopped by pid): Debian's
// mosquitto broker on a free loopback port with its own config in a temp dir, and a third-party
// subscriber (mqtt_subscriber.py, python3-paho-mqtt) whose JSON lines are collected here.

#include <arpa/inet.h>
#include <fcntl.h>
#include <google/protobuf/struct.pb.h>
#include <google/protobuf/util/json_util.h>
#include <netinet/in.h>
#include <pwd.h>
#include <signal.h>
#include <spawn.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <fstream>
#include <functional>
#include <mutex>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "tests/support/test_paths.hpp"

extern char** environ;

namespace springscan::daemon::testing {

/// A loopback port that was free a moment ago (bound to port 0 and released).
inline int free_loopback_port() {
  const int fd = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  socklen_t len = sizeof addr;
  if (::bind(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr) != 0 ||
      ::getsockname(fd, reinterpret_cast<sockaddr*>(&addr), &len) != 0) {
    ::close(fd);
    throw std::runtime_error("no free loopback port");
  }
  ::close(fd);
  return ntohs(addr.sin_port);
}

inline bool accepts_connections(int port) {
  const int fd = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  addr.sin_port = htons(static_cast<std::uint16_t>(port));
  const bool ok = ::connect(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr) == 0;
  ::close(fd);
  return ok;
}

/// Spawns `argv` with stdout to `stdout_fd` (or the log file) and stderr to `log_path`.
inline pid_t spawn(const std::vector<std::string>& argv, const std::string& log_path,
                   int stdout_fd = -1) {
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 2, log_path.c_str(), O_WRONLY | O_CREAT | O_APPEND,
                                   0644);
  if (stdout_fd >= 0) {
    posix_spawn_file_actions_adddup2(&actions, stdout_fd, 1);
  } else {
    posix_spawn_file_actions_adddup2(&actions, 2, 1);
  }
  std::vector<std::string> copy = argv;
  std::vector<char*> args;
  for (auto& a : copy) args.push_back(a.data());
  args.push_back(nullptr);
  pid_t pid = -1;
  const int rc = posix_spawnp(&pid, args[0], &actions, nullptr, args.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (rc != 0) throw std::runtime_error("cannot start " + argv[0]);
  return pid;
}

inline int stop_child(pid_t pid, int signal) {
  int status = 0;
  ::kill(pid, signal);
  for (int i = 0; i < 500; ++i) {
    if (::waitpid(pid, &status, WNOHANG) == pid) return status;
    ::usleep(10000);
  }
  ::kill(pid, SIGKILL);
  ::waitpid(pid, &status, 0);
  return status;
}

struct BrokerTls {
  std::string ca_file, cert_file, key_file;  ///< empty: plain MQTT
};

/// mosquitto on 127.0.0.1:port() with a config of its own in `dir`. With `persistent`, its
/// state (a subscriber's session and queued messages) survives stop() + start() as it does
/// in a plant broker with persistence; otherwise nothing is written.
class MosquittoBroker {
 public:
  MosquittoBroker(std::string dir, bool persistent, BrokerTls tls = {})
      : dir_(std::move(dir)), port_(free_loopback_port()) {
    std::ofstream conf(dir_ + "/mosquitto.conf");
    // Started as root, mosquitto would switch to user "mosquitto", who cannot write here.
    const passwd* me = ::getpwuid(::getuid());
    conf << "per_listener_settings false\nallow_anonymous true\nuser "
         << (me != nullptr ? me->pw_name : "root") << "\n";
    if (persistent) {
      conf << "persistence true\npersistence_location " << dir_
           << "/\npersistence_file mosquitto.db\nautosave_interval 1\n";
    } else {
      conf << "persistence false\n";
    }
    conf << "listener " << port_ << " 127.0.0.1\n";
    if (!tls.ca_file.empty()) {
      conf << "cafile " << tls.ca_file << "\ncertfile " << tls.cert_file << "\nkeyfile "
           << tls.key_file << "\n";
    }
    conf.close();
    start();
  }
  ~MosquittoBroker() { stop(); }
  MosquittoBroker(const MosquittoBroker&) = delete;
  MosquittoBroker& operator=(const MosquittoBroker&) = delete;

  int port() const { return port_; }
  bool running() const { return pid_ > 0; }

  void start(double timeout_s = 10.0) {
    if (pid_ > 0) return;
    pid_ = spawn({"mosquitto", "-c", dir_ + "/mosquitto.conf"}, dir_ + "/mosquitto.log");
    const auto deadline =
        std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
    while (std::chrono::steady_clock::now() < deadline) {
      if (accepts_connections(port_)) return;
      int status = 0;
      if (::waitpid(pid_, &status, WNOHANG) == pid_) {
        pid_ = -1;
        throw std::runtime_error("mosquitto exited at start: " + log());
      }
      ::usleep(20000);
    }
    stop();  // a throwing constructor runs no destructor: never leave the broker behind
    throw std::runtime_error("mosquitto does not accept connections on port " +
                             std::to_string(port_) + ": " + log());
  }
  /// Stops the broker by pid (SIGTERM: with persistence it saves its state first).
  void stop(int signal = SIGTERM) {
    if (pid_ <= 0) return;
    stop_child(pid_, signal);
    pid_ = -1;
  }
  std::string log() const {
    std::ifstream in(dir_ + "/mosquitto.log");
    return std::string(std::istreambuf_iterator<char>(in), {});
  }

 private:
  std::string dir_;
  int port_;
  pid_t pid_ = -1;
};

/// One line of the subscriber's output, parsed.
using Message = google::protobuf::Struct;

inline std::string field(const Message& m, const std::string& name) {
  const auto found = m.fields().find(name);
  return found == m.fields().end() ? "" : found->second.string_value();
}
inline double number(const Message& m, const std::string& name) {
  const auto found = m.fields().find(name);
  return found == m.fields().end() ? 0.0 : found->second.number_value();
}
inline std::string prop(const Message& m, const std::string& name) {
  const auto props = m.fields().find("props");
  if (props == m.fields().end()) return "";
  const auto found = props->second.struct_value().fields().find(name);
  return found == props->second.struct_value().fields().end() ? "" : found->second.string_value();
}

/// mqtt_subscriber.py subscribed to `prefix`/# on the broker; collects what it prints.
class PahoSubscriber {
 public:
  PahoSubscriber(const std::string& script, const std::string& dir, int port,
                 const std::string& prefix, const std::vector<std::string>& extra = {}) {
    int fds[2];
    if (::pipe2(fds, O_CLOEXEC) != 0) throw std::runtime_error("pipe");
    std::vector<std::string> argv = {springscan::test_paths::kPython3,
                                     "-u",
                                     script,
                                     "--port",
                                     std::to_string(port),
                                     "--prefix",
                                     prefix};
    argv.insert(argv.end(), extra.begin(), extra.end());
    pid_ = spawn(argv, dir + "/subscriber.log", fds[1]);
    ::close(fds[1]);
    read_fd_ = fds[0];
    reader_ = std::thread([this] { read_lines(); });
  }
  ~PahoSubscriber() {
    stop_child(pid_, SIGTERM);
    reader_.join();
    ::close(read_fd_);
  }
  PahoSubscriber(const PahoSubscriber&) = delete;
  PahoSubscriber& operator=(const PahoSubscriber&) = delete;

  std::vector<Message> messages() {
    std::lock_guard lock(mutex_);
    return messages_;
  }
  /// Waits until `done(messages)` holds; false after `timeout_s`.
  bool wait_for(const std::function<bool(const std::vector<Message>&)>& done, double timeout_s) {
    std::unique_lock lock(mutex_);
    return changed_.wait_for(lock, std::chrono::duration<double>(timeout_s),
                             [&] { return done(messages_); });
  }
  /// Messages of `topic`.
  static std::vector<Message> on(const std::vector<Message>& all, const std::string& topic) {
    std::vector<Message> out;
    for (const auto& m : all)
      if (field(m, "topic") == topic) out.push_back(m);
    return out;
  }
  static int count_events(const std::vector<Message>& all, const std::string& event) {
    int n = 0;
    for (const auto& m : all) n += field(m, "event") == event ? 1 : 0;
    return n;
  }

 private:
  void read_lines() {
    std::string pending;
    char buffer[65536];
    while (true) {
      const ssize_t n = ::read(read_fd_, buffer, sizeof buffer);
      if (n <= 0) break;
      pending.append(buffer, static_cast<std::size_t>(n));
      std::size_t at;
      while ((at = pending.find('\n')) != std::string::npos) {
        Message m;
        const auto status = google::protobuf::util::JsonStringToMessage(pending.substr(0, at), &m);
        pending.erase(0, at + 1);
        if (!status.ok()) continue;
        {
          std::lock_guard lock(mutex_);
          messages_.push_back(std::move(m));
        }
        changed_.notify_all();
      }
    }
  }

  pid_t pid_ = -1;
  int read_fd_ = -1;
  std::thread reader_;
  std::mutex mutex_;
  std::condition_variable changed_;
  std::vector<Message> messages_;
};

}  // namespace springscan::daemon::testing
