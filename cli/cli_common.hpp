#pragma once
// What every springscan subcommand shares: exit codes, a small option parser that writes the
// --help text from the options it knows, and a stderr logger with levels.

#include <map>
#include <optional>
#include <string>
#include <vector>

namespace springscan::cli {

/// Exit codes of every subcommand (README.md "Usage").
enum ExitCode : int {
  kExitOk = 0,              ///< the command ran (for analyze: whatever the verdict)
  kExitAnalysisFailed = 1,  ///< input was readable but the analysis could not be completed
  kExitUsage = 2,           ///< bad usage or unreadable input
};

enum class LogLevel { kDebug, kInfo, kWarning, kError, kQuiet };

/// Logs to stderr, one line per message, prefixed with the level. Not thread-safe by design:
/// the CLI logs from its main thread only.
class Logger {
 public:
  void set_level(LogLevel level) { level_ = level; }
  LogLevel level() const { return level_; }
  void debug(const std::string& message) const { write(LogLevel::kDebug, message); }
  void info(const std::string& message) const { write(LogLevel::kInfo, message); }
  void warning(const std::string& message) const { write(LogLevel::kWarning, message); }
  void error(const std::string& message) const { write(LogLevel::kError, message); }
  /// A transient progress line ("\r..."), shown only when stderr is a terminal and not quiet.
  void progress(const std::string& message) const;
  /// Ends a progress line, if one is showing.
  void end_progress() const;

 private:
  void write(LogLevel level, const std::string& message) const;
  LogLevel level_ = LogLevel::kInfo;
  mutable bool progress_showing_ = false;
};

/// Parses `--name value`, `--name=value`, `--switch` and positionals. Every command gets
/// --help, --quiet and --log-level LEVEL for free.
class ArgParser {
 public:
  ArgParser(std::string command, std::string usage, std::string description);

  void add_option(const std::string& name, const std::string& value_name, const std::string& help);
  void add_switch(const std::string& name, const std::string& help);

  enum class Outcome { kRun, kHelpShown, kUsageError };
  /// Parses argv[first..argc). On kUsageError the message is in error(); on kHelpShown the help
  /// text went to stdout.
  Outcome parse(int argc, char** argv, int first = 1);

  std::string help() const;
  const std::string& error() const { return error_; }
  bool has(const std::string& name) const { return values_.count(name) != 0; }
  std::string get(const std::string& name, const std::string& fallback = "") const;
  /// Every value an option was given, in order (`--scan A --scan B`); get() has the last.
  std::vector<std::string> get_all(const std::string& name) const;
  /// The option as a number; a usage error (in error()) when it is present but not a number.
  std::optional<double> get_number(const std::string& name);
  const std::vector<std::string>& positionals() const { return positionals_; }

  /// Applies --quiet and --log-level to the logger.
  bool configure_logger(Logger& logger);

  /// parse() from argv[2] plus configure_logger(): the opening of every subcommand. Returns the
  /// exit code to return at once (--help shown, or a usage error already printed), or nothing
  /// when the command should run.
  std::optional<int> start(int argc, char** argv, Logger& logger);

 private:
  struct Spec {
    std::string value_name;  // empty for a switch
    std::string help;
  };
  std::string command_, usage_, description_, error_;
  std::vector<std::string> order_;
  std::map<std::string, Spec> specs_;
  std::map<std::string, std::string> values_;
  std::map<std::string, std::vector<std::string>> all_values_;
  std::vector<std::string> positionals_;
};

/// Prints "springscan COMMAND: message" on stderr and returns `code`: the one-line reason the
/// DESIGN.md contract asks for when a command cannot run.
int fail_with(const std::string& command, const std::string& message, int code);

}  // namespace springscan::cli
