#pragma once
// Headless Chromium driven over the DevTools protocol on a pipe (--remote-debugging-pipe: the
// browser reads commands on fd 3 and writes answers on fd 4, each a JSON message ended by a NUL
// byte), so a test can read the live DOM of a page that keeps changing, without a WebSocket
// client. Flags as tests/report/browser_test.cpp runs it; a fresh profile directory; the
// browser runs in its own process group, killed (with its helpers) by the destructor.
//
// Runtime.evaluate returns the value of a JavaScript expression that must evaluate to a
// string; the test keeps its own format inside that string, so no JSON parser is needed here.

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

namespace springscan::daemon::testing {

inline std::string find_chromium() {
  const char* path = std::getenv("PATH");
  std::stringstream dirs(path ? path : "/usr/bin:/bin");
  for (std::string dir; std::getline(dirs, dir, ':');)
    for (const char* name : {"chromium", "chromium-browser"})
      if (!dir.empty() && ::access((std::filesystem::path(dir) / name).c_str(), X_OK) == 0)
        return (std::filesystem::path(dir) / name).string();
  return "";
}

/// A JSON string literal's text (escapes undone; \u only for ASCII, all this test needs).
inline std::string json_unescape(const std::string& text, std::size_t& at) {
  std::string out;
  for (; at < text.size() && text[at] != '"'; ++at) {
    if (text[at] != '\\' || at + 1 >= text.size()) {
      out.push_back(text[at]);
      continue;
    }
    const char e = text[++at];
    if (e == 'n')
      out.push_back('\n');
    else if (e == 't')
      out.push_back('\t');
    else if (e == 'u' && at + 4 < text.size()) {
      out.push_back(static_cast<char>(std::stoi(text.substr(at + 1, 4), nullptr, 16)));
      at += 4;
    } else
      out.push_back(e);
  }
  return out;
}

/// JavaScript source as a JSON string literal.
inline std::string json_quote(const std::string& text) {
  std::string out = "\"";
  for (const char c : text) {
    if (c == '"' || c == '\\') out.push_back('\\');
    if (c == '\n') {
      out += "\\n";
      continue;
    }
    out.push_back(c);
  }
  return out + "\"";
}

class CdpBrowser {
 public:
  /// Starts Chromium on `url` with its profile in `profile_dir`.
  CdpBrowser(const std::string& chromium, const std::string& url, const std::string& profile_dir) {
    int to_browser[2], from_browser[2];
    if (::pipe2(to_browser, O_CLOEXEC) != 0 || ::pipe2(from_browser, O_CLOEXEC) != 0) return;
    const std::vector<std::string> argv = {
        chromium, "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
        "--disable-background-networking", "--disable-component-update", "--disable-sync",
        // A page in the background must not be throttled:
        // its timers and rendering are what is measured.
        "--disable-background-timer-throttling", "--disable-renderer-backgrounding",
        "--remote-debugging-pipe", "--user-data-dir=" + profile_dir, "--window-size=1280,1600",
        url};
    // Built before fork(): the child of a threaded process may only call async-signal-safe
    // functions until execv, and malloc is not one.
    std::vector<char*> args;
    for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
    args.push_back(nullptr);
    pid_ = ::fork();
    if (pid_ == 0) {
      ::setpgid(0, 0);
      // fd 3 and 4 as the protocol wants them (dup2 clears close-on-exec).
      ::dup2(to_browser[0], 3);
      ::dup2(from_browser[1], 4);
      const int null = ::open("/dev/null", O_WRONLY);
      ::dup2(null, STDOUT_FILENO);
      ::dup2(null, STDERR_FILENO);
      ::execv(args[0], args.data());
      ::_exit(127);
    }
    ::setpgid(pid_, pid_);
    ::close(to_browser[0]);
    ::close(from_browser[1]);
    write_fd_ = to_browser[1];
    read_fd_ = from_browser[0];
  }
  ~CdpBrowser() {
    if (write_fd_ >= 0) ::close(write_fd_);
    if (read_fd_ >= 0) ::close(read_fd_);
    if (pid_ > 0) {
      ::kill(-pid_, SIGKILL);
      ::waitpid(pid_, nullptr, 0);
    }
  }
  CdpBrowser(const CdpBrowser&) = delete;
  CdpBrowser& operator=(const CdpBrowser&) = delete;

  /// Attaches to the page target (the url given at start). False after `timeout`.
  bool attach(std::chrono::milliseconds timeout) {
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    while (std::chrono::steady_clock::now() < deadline) {
      const auto targets = call("Target.getTargets", "{}", "", deadline);
      const std::size_t page = targets ? targets->find("\"type\":\"page\"") : std::string::npos;
      if (page == std::string::npos) {
        ::usleep(100000);
        continue;
      }
      const std::size_t id = targets->rfind("\"targetId\":\"", page);
      if (id == std::string::npos) return false;
      std::size_t at = id + 12;
      const std::string target = json_unescape(*targets, at);
      const auto attached =
          call("Target.attachToTarget", "{\"targetId\":\"" + target + "\",\"flatten\":true}", "",
               deadline);
      const std::size_t s = attached ? attached->find("\"sessionId\":\"") : std::string::npos;
      if (s == std::string::npos) return false;
      at = s + 13;
      session_ = json_unescape(*attached, at);
      return true;
    }
    return false;
  }

  /// The string value of `expression` in the page; nullopt on an error or after `timeout`.
  std::optional<std::string> evaluate(
      const std::string& expression, std::chrono::milliseconds timeout = std::chrono::seconds(10)) {
    const auto answer =
        call("Runtime.evaluate",
             "{\"expression\":" + json_quote(expression) + ",\"returnByValue\":true}", session_,
             std::chrono::steady_clock::now() + timeout);
    const std::string key = "\"type\":\"string\",\"value\":\"";
    const std::size_t v = answer ? answer->find(key) : std::string::npos;
    if (v == std::string::npos) return std::nullopt;
    std::size_t at = v + key.size();
    return json_unescape(*answer, at);
  }

 private:
  // Sends one command and returns its answer (the message with the same id); events and other
  // answers in between are skipped.
  std::optional<std::string> call(const std::string& method, const std::string& params,
                                  const std::string& session,
                                  std::chrono::steady_clock::time_point deadline) {
    const int id = ++next_id_;
    std::string message =
        "{\"id\":" + std::to_string(id) + ",\"method\":\"" + method + "\",\"params\":" + params;
    if (!session.empty()) message += ",\"sessionId\":\"" + session + "\"";
    message += "}";
    message.push_back('\0');
    if (::write(write_fd_, message.data(), message.size()) != static_cast<ssize_t>(message.size()))
      return std::nullopt;
    const std::string tag = "{\"id\":" + std::to_string(id) + ",";
    for (;;) {
      for (std::size_t end; (end = buffer_.find('\0')) != std::string::npos;) {
        std::string one = buffer_.substr(0, end);
        buffer_.erase(0, end + 1);
        if (one.rfind(tag, 0) == 0) return one;
      }
      const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
          deadline - std::chrono::steady_clock::now());
      if (left.count() <= 0) return std::nullopt;
      pollfd p{read_fd_, POLLIN, 0};
      if (::poll(&p, 1, static_cast<int>(left.count())) <= 0) return std::nullopt;
      char chunk[65536];
      const ssize_t n = ::read(read_fd_, chunk, sizeof chunk);
      if (n <= 0) return std::nullopt;
      buffer_.append(chunk, static_cast<std::size_t>(n));
    }
  }

  pid_t pid_ = -1;
  int write_fd_ = -1;
  int read_fd_ = -1;
  int next_id_ = 0;
  std::string session_;
  std::string buffer_;
};

}  // namespace springscan::daemon::testing
