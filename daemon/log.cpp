#include "daemon/log.hpp"

#include <cstdlib>

namespace springscan::daemon {

std::optional<LogLevel> parse_log_level(std::string_view name) {
  if (name == "debug") return LogLevel::kDebug;
  if (name == "info") return LogLevel::kInfo;
  if (name == "warning") return LogLevel::kWarning;
  if (name == "error") return LogLevel::kError;
  return std::nullopt;
}

Log::Log(LogLevel min_level, std::FILE* out, bool journal_prefix)
    : min_level_(min_level), out_(out), journal_prefix_(journal_prefix) {}

Log Log::to_stderr(LogLevel min_level) {
  return Log(min_level, stderr, std::getenv("JOURNAL_STREAM") != nullptr);
}

void Log::set_level(LogLevel level) {
  std::lock_guard lock(mutex_);
  min_level_ = level;
}

LogLevel Log::level() const {
  std::lock_guard lock(mutex_);
  return min_level_;
}

void Log::write(LogLevel level, std::string_view message) {
  std::lock_guard lock(mutex_);
  if (level < min_level_ || out_ == nullptr) return;
  // sd-daemon(3): <3> SD_ERR, <4> SD_WARNING, <6> SD_INFO, <7> SD_DEBUG.
  static constexpr const char* kJournal[] = {"<7>", "<6>", "<4>", "<3>"};
  static constexpr const char* kPlain[] = {"debug: ", "info: ", "WARNING: ", "ERROR: "};
  const auto index = static_cast<int>(level);
  std::fprintf(out_, "%s%.*s\n", journal_prefix_ ? kJournal[index] : kPlain[index],
               static_cast<int>(message.size()), message.data());
  std::fflush(out_);
}

}  // namespace springscan::daemon
