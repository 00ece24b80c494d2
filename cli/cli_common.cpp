#include "cli/cli_common.hpp"

#include <unistd.h>

#include <charconv>
#include <cstdio>
#include <iostream>
#include <sstream>

namespace springscan::cli {
namespace {

const char* level_name(LogLevel level) {
  switch (level) {
    case LogLevel::kDebug:
      return "debug";
    case LogLevel::kInfo:
      return "info";
    case LogLevel::kWarning:
      return "warning";
    case LogLevel::kError:
      return "error";
    case LogLevel::kQuiet:
      return "quiet";
  }
  return "?";
}

std::optional<LogLevel> parse_level(const std::string& text) {
  for (auto level : {LogLevel::kDebug, LogLevel::kInfo, LogLevel::kWarning, LogLevel::kError,
                     LogLevel::kQuiet}) {
    if (text == level_name(level)) return level;
  }
  return std::nullopt;
}

}  // namespace

void Logger::write(LogLevel level, const std::string& message) const {
  if (level < level_ || level_ == LogLevel::kQuiet) return;
  end_progress();
  std::cerr << level_name(level) << ": " << message << '\n';
}

void Logger::progress(const std::string& message) const {
  if (level_ > LogLevel::kInfo || !isatty(STDERR_FILENO)) return;
  std::cerr << "\r\033[K" << message << std::flush;
  progress_showing_ = true;
}

void Logger::end_progress() const {
  if (!progress_showing_) return;
  std::cerr << "\r\033[K" << std::flush;
  progress_showing_ = false;
}

ArgParser::ArgParser(std::string command, std::string usage, std::string description)
    : command_(std::move(command)), usage_(std::move(usage)), description_(std::move(description)) {
  add_switch("help", "show this help and exit");
  add_switch("quiet", "print nothing but errors");
  add_option("log-level", "LEVEL", "debug, info (default), warning, error or quiet");
}

void ArgParser::add_option(const std::string& name, const std::string& value_name,
                           const std::string& help) {
  order_.push_back(name);
  specs_[name] = Spec{value_name, help};
}

void ArgParser::add_switch(const std::string& name, const std::string& help) {
  order_.push_back(name);
  specs_[name] = Spec{"", help};
}

ArgParser::Outcome ArgParser::parse(int argc, char** argv, int first) {
  for (int i = first; i < argc; ++i) {
    std::string arg = argv[i];
    if (arg.rfind("--", 0) != 0 || arg == "--") {
      positionals_.push_back(arg);
      continue;
    }
    std::string name = arg.substr(2);
    std::optional<std::string> inline_value;
    if (auto eq = name.find('='); eq != std::string::npos) {
      inline_value = name.substr(eq + 1);
      name = name.substr(0, eq);
    }
    auto spec = specs_.find(name);
    if (spec == specs_.end()) {
      error_ = "unknown option --" + name + " (see springscan " + command_ + " --help)";
      return Outcome::kUsageError;
    }
    if (spec->second.value_name.empty()) {
      if (inline_value) {
        error_ = "option --" + name + " takes no value";
        return Outcome::kUsageError;
      }
      values_.insert_or_assign(name,
                               std::string(1, '1'));  // not ="1": g++ 12 -Wrestrict false positive
    } else if (inline_value || i + 1 < argc) {
      values_[name] = inline_value ? *inline_value : argv[++i];
      all_values_[name].push_back(values_[name]);
    } else {
      error_ = "option --" + name + " needs a value (" + spec->second.value_name + ")";
      return Outcome::kUsageError;
    }
  }
  if (has("help")) {
    std::cout << help();
    return Outcome::kHelpShown;
  }
  return Outcome::kRun;
}

std::string ArgParser::help() const {
  std::ostringstream out;
  // Commands give either the whole usage line or only what follows their name.
  const bool whole_line = usage_.rfind("springscan ", 0) == 0;
  out << "usage: " << (whole_line ? "" : "springscan " + command_ + ' ') << usage_ << "\n\n"
      << description_ << "\n\n";
  out << "options:\n";
  for (const auto& name : order_) {
    const Spec& spec = specs_.at(name);
    std::string left = "  --" + name + (spec.value_name.empty() ? "" : " " + spec.value_name);
    if (left.size() < 30)
      left.resize(30, ' ');
    else
      left += "\n" + std::string(30, ' ');
    out << left << spec.help << '\n';
  }
  return out.str();
}

std::vector<std::string> ArgParser::get_all(const std::string& name) const {
  const auto found = all_values_.find(name);
  return found == all_values_.end() ? std::vector<std::string>{} : found->second;
}

std::string ArgParser::get(const std::string& name, const std::string& fallback) const {
  auto it = values_.find(name);
  return it == values_.end() ? fallback : it->second;
}

std::optional<double> ArgParser::get_number(const std::string& name) {
  auto it = values_.find(name);
  if (it == values_.end()) return std::nullopt;
  double value = 0.0;
  const char* begin = it->second.data();
  const char* end = begin + it->second.size();
  auto [ptr, ec] = std::from_chars(begin, end, value);
  if (ec != std::errc() || ptr != end) {
    error_ = "option --" + name + " expects a number, got '" + it->second + "'";
    return std::nullopt;
  }
  return value;
}

bool ArgParser::configure_logger(Logger& logger) {
  if (has("log-level")) {
    auto level = parse_level(get("log-level"));
    if (!level) {
      error_ = "--log-level expects debug, info, warning, error or quiet, got '" +
               get("log-level") + "'";
      return false;
    }
    logger.set_level(*level);
  }
  if (has("quiet")) logger.set_level(LogLevel::kError);
  return true;
}

std::optional<int> ArgParser::start(int argc, char** argv, Logger& logger) {
  switch (parse(argc, argv, 2)) {
    case Outcome::kHelpShown:
      return kExitOk;
    case Outcome::kUsageError:
      return fail_with(command_, error_, kExitUsage);
    case Outcome::kRun:
      break;
  }
  if (!configure_logger(logger)) return fail_with(command_, error_, kExitUsage);
  return std::nullopt;
}

int fail_with(const std::string& command, const std::string& message, int code) {
  std::cerr << "springscan " << command << ": " << message << '\n';
  return code;
}

}  // namespace springscan::cli
