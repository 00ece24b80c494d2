#pragma once
// The daemon's logger: one line per event on stderr, with a level. Under systemd (JOURNAL_STREAM
// set) each line starts with the sd-daemon(3) priority prefix "<N>" so journald stores the level;
// on a terminal it starts with the level name. Thread-safe: the event loop and the job runner
// both log. Messages follow one pattern a technician can act on at 3 a.m.:
// what happened, which part/job, and what to do.

#include <cstdio>
#include <mutex>
#include <optional>
#include <string>
#include <string_view>

namespace springscan::daemon {

enum class LogLevel { kDebug = 0, kInfo = 1, kWarning = 2, kError = 3 };

/// "debug", "info", "warning", "error" -> the level; anything else -> nullopt.
std::optional<LogLevel> parse_log_level(std::string_view name);

class Log {
 public:
  /// Writes to `out` (not owned; must outlive the logger). `journal_prefix` selects "<N>".
  Log(LogLevel min_level, std::FILE* out, bool journal_prefix);
  /// stderr, with the journald prefix when JOURNAL_STREAM is set.
  static Log to_stderr(LogLevel min_level);

  void set_level(LogLevel level);
  LogLevel level() const;
  void debug(std::string_view message) { write(LogLevel::kDebug, message); }
  void info(std::string_view message) { write(LogLevel::kInfo, message); }
  void warning(std::string_view message) { write(LogLevel::kWarning, message); }
  void error(std::string_view message) { write(LogLevel::kError, message); }
  void write(LogLevel level, std::string_view message);

 private:
  mutable std::mutex mutex_;
  LogLevel min_level_;
  std::FILE* out_;
  bool journal_prefix_;
};

}  // namespace springscan::daemon
