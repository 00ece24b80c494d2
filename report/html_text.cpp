#include "report/html_text.hpp"

#include <cmath>
#include <cstdio>
#include <cstring>

namespace springscan::report {

std::string escape_html(std::string_view text) {
  std::string out;
  out.reserve(text.size() + text.size() / 8);
  for (char c : text) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      case '\'':
        out += "&#39;";
        break;
      default:
        out.push_back(c);
    }
  }
  return out;
}

std::string base64(std::string_view bytes) {
  static constexpr char kAlphabet[] =
      "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((bytes.size() + 2) / 3 * 4);
  std::size_t i = 0;
  for (; i + 2 < bytes.size(); i += 3) {
    const unsigned v = (static_cast<unsigned char>(bytes[i]) << 16) |
                       (static_cast<unsigned char>(bytes[i + 1]) << 8) |
                       static_cast<unsigned char>(bytes[i + 2]);
    out.push_back(kAlphabet[(v >> 18) & 63]);
    out.push_back(kAlphabet[(v >> 12) & 63]);
    out.push_back(kAlphabet[(v >> 6) & 63]);
    out.push_back(kAlphabet[v & 63]);
  }
  const std::size_t rest = bytes.size() - i;
  if (rest > 0) {
    unsigned v = static_cast<unsigned char>(bytes[i]) << 16;
    if (rest == 2) v |= static_cast<unsigned char>(bytes[i + 1]) << 8;
    out.push_back(kAlphabet[(v >> 18) & 63]);
    out.push_back(kAlphabet[(v >> 12) & 63]);
    out.push_back(rest == 2 ? kAlphabet[(v >> 6) & 63] : '=');
    out.push_back('=');
  }
  return out;
}

std::string fixed(double value, int decimals) {
  if (!std::isfinite(value)) return "n/a";
  char text[64];
  std::snprintf(text, sizeof text, "%.*f", decimals, value);
  // "-0.00" (a tiny negative value) prints as "0.00".
  const bool negative_zero = text[0] == '-' && std::strspn(text + 1, "0.") == std::strlen(text + 1);
  return negative_zero ? text + 1 : text;
}

// Both below work in a char buffer: string insert/assign of short literals here trips g++ 12's
// -Wrestrict false positive under -O2 with sanitizers.
std::string signed_fixed(double value, int decimals) {
  const std::string out = fixed(value, decimals);
  if (out == "n/a" || out[0] == '-' || out.find_first_not_of("0.") == std::string::npos) return out;
  char text[80];
  std::snprintf(text, sizeof text, "+%s", out.c_str());
  return text;
}

std::string svg_number(double value) {
  char text[64] = "0";
  if (std::isfinite(value)) std::snprintf(text, sizeof text, "%.2f", value);
  std::size_t n = std::strlen(text);
  if (std::strchr(text, '.')) {
    while (n > 0 && text[n - 1] == '0') --n;
    if (n > 0 && text[n - 1] == '.') --n;
  }
  const std::string_view trimmed(text, n);
  return std::string(trimmed == "-0" ? std::string_view("0") : trimmed);
}

}  // namespace springscan::report
