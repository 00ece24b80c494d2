#include "report/colormap.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>

namespace springscan::report {
namespace {

// Stops at t = -1, -0.5, 0, 0.5, 1 of the scale: blue, cyan, green, yellow, red.
constexpr std::array<Rgb, 5> kStops = {
    {{32, 64, 208}, {0, 176, 232}, {40, 184, 72}, {248, 200, 0}, {216, 36, 36}}};

}  // namespace

Rgb deviation_color(double deviation_mm, double scale_mm) {
  if (!std::isfinite(deviation_mm) || !(scale_mm > 0.0)) return {150, 150, 150};
  const double t = std::clamp(deviation_mm / scale_mm, -1.0, 1.0);
  const double s = (t + 1.0) * 2.0;  // 0 .. 4 over the stops
  const int i = std::min(static_cast<int>(s), 3);
  const double f = s - i;
  Rgb out{};
  for (int c = 0; c < 3; ++c) {
    const double a = kStops[static_cast<std::size_t>(i)][static_cast<std::size_t>(c)];
    const double b = kStops[static_cast<std::size_t>(i + 1)][static_cast<std::size_t>(c)];
    out[static_cast<std::size_t>(c)] = static_cast<std::uint8_t>(std::lround(a + (b - a) * f));
  }
  return out;
}

std::string css_color(Rgb color) {
  char text[8];
  std::snprintf(text, sizeof text, "#%02x%02x%02x", color[0], color[1], color[2]);
  return text;
}

}  // namespace springscan::report
