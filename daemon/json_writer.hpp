#pragma once
// A minimal JSON writer for the daemon's own payloads: the MQTT result summary
// (result_summary.cpp) and the operator page's event stream (page_feed.cpp). One writer, so the
// two agree on escaping and number formatting.

#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <string>
#include <string_view>

namespace springscan::daemon {

/// A minimal JSON writer: objects and arrays with comma handling, escaped strings, numbers in
/// their shortest round-trip form (non-finite numbers become null, as JSON has no NaN).
class JsonWriter {
 public:
  void begin_object(std::string_view key = {}) { open(key, '{'); }
  void end_object() { close('}'); }
  void begin_array(std::string_view key) { open(key, '['); }
  void end_array() { close(']'); }

  void field(std::string_view key, std::string_view value) {
    prefix(key);
    string(value);
  }
  void field(std::string_view key, const char* value) { field(key, std::string_view(value)); }
  void field(std::string_view key, bool value) {
    prefix(key);
    out_ += value ? "true" : "false";
  }
  void field(std::string_view key, double value) {
    prefix(key);
    number(value);
  }
  void field(std::string_view key, std::int64_t value) {
    prefix(key);
    out_ += std::to_string(value);
  }
  void field(std::string_view key, std::uint64_t value) {
    prefix(key);
    out_ += std::to_string(value);
  }
  void element(std::string_view value) {
    prefix({});
    string(value);
  }

  std::string take() { return std::move(out_); }

 private:
  void open(std::string_view key, char bracket) {
    prefix(key);
    out_.push_back(bracket);
    first_ = true;
  }
  void close(char bracket) {
    out_.push_back(bracket);
    first_ = false;
  }
  void prefix(std::string_view key) {
    if (!first_) out_.push_back(',');
    first_ = false;
    if (!key.empty()) {
      string(key);
      out_.push_back(':');
    }
  }
  void string(std::string_view text) {
    out_.push_back('"');
    for (const char c : text) {
      switch (c) {
        case '"':
          out_ += "\\\"";
          break;
        case '\\':
          out_ += "\\\\";
          break;
        case '\n':
          out_ += "\\n";
          break;
        case '\r':
          out_ += "\\r";
          break;
        case '\t':
          out_ += "\\t";
          break;
        default:
          if (static_cast<unsigned char>(c) < 0x20) {
            char escaped[8];
            std::snprintf(escaped, sizeof escaped, "\\u%04x", static_cast<unsigned>(c));
            out_ += escaped;
          } else {
            out_.push_back(c);
          }
      }
    }
    out_.push_back('"');
  }
  void number(double value) {
    if (!std::isfinite(value)) {
      out_ += "null";
      return;
    }
    char buffer[32];
    const auto result = std::to_chars(buffer, buffer + sizeof buffer, value);
    out_.append(buffer, result.ptr);
  }

  std::string out_;
  bool first_ = true;
};

}  // namespace springscan::daemon
