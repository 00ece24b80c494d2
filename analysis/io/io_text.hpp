#pragma once
// Internal to the point readers (ply_*.cpp, xyz_io.cpp, stl_io.cpp): a whitespace tokenizer
// over untrusted text that tracks the line number for error messages, and number parsing.

#include <charconv>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

namespace springscan::analysis::io_detail {

/// Reads whitespace-separated tokens from `text`, counting lines (1-based). Does not own text.
class TextCursor {
 public:
  TextCursor(std::string_view text, std::size_t first_line) : text_(text), line_(first_line) {}

  /// The next token, or an empty view at the end of the text (line() then stays on the last
  /// line that had a token, which is where a truncated file's error belongs).
  std::string_view next() {
    const std::size_t line_before = line_;
    while (pos_ < text_.size() && is_space(text_[pos_])) {
      if (text_[pos_] == '\n') ++line_;
      ++pos_;
    }
    if (pos_ == text_.size()) line_ = line_before;
    const std::size_t begin = pos_;
    while (pos_ < text_.size() && !is_space(text_[pos_])) ++pos_;
    return text_.substr(begin, pos_ - begin);
  }
  std::size_t line() const { return line_; }
  std::size_t remaining() const { return text_.size() - pos_; }

  static bool is_space(char c) {
    return c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\v' || c == '\f';
  }

 private:
  std::string_view text_;
  std::size_t pos_ = 0;
  std::size_t line_;
};

/// The whole token as a double ("1", "-2.5e3", "+4", "nan", "inf" all parse), or nullopt.
inline std::optional<double> parse_double(std::string_view token) {
  if (!token.empty() && token.front() == '+') token.remove_prefix(1);
  double value = 0.0;
  const char* end = token.data() + token.size();
  const auto [ptr, ec] = std::from_chars(token.data(), end, value);
  if (ec != std::errc() || ptr != end || token.empty()) return std::nullopt;
  return value;
}

/// The whole token as an unsigned integer, or nullopt (also on overflow).
inline std::optional<std::uint64_t> parse_count(std::string_view token) {
  std::uint64_t value = 0;
  const char* end = token.data() + token.size();
  const auto [ptr, ec] = std::from_chars(token.data(), end, value);
  if (ec != std::errc() || ptr != end || token.empty()) return std::nullopt;
  return value;
}

/// "'token'", shortened so that a binary blob does not flood an error message.
inline std::string quoted(std::string_view token) {
  constexpr std::size_t kMax = 40;
  std::string out = "'";
  for (char c : token.substr(0, kMax)) out += (c >= 32 && c < 127) ? c : '?';
  if (token.size() > kMax) out += "...";
  return out + "'";
}

/// Lower-case copy (ASCII).
inline std::string lower(std::string_view text) {
  std::string out(text);
  for (char& c : out) {
    if (c >= 'A' && c <= 'Z') c = static_cast<char>(c - 'A' + 'a');
  }
  return out;
}

}  // namespace springscan::analysis::io_detail
