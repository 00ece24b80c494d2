#include "drivers/genicam/range_lines.hpp"

#include <cmath>
#include <cstdio>
#include <cstring>

namespace springscan::drivers::genicam {
namespace {

// PFNC data is little-endian (GigE Vision and USB3 Vision alike), as is every host we build for.
float load_f32(const std::uint8_t* p) {
  float v;
  std::memcpy(&v, p, sizeof v);
  return v;
}
std::uint16_t load_u16(const std::uint8_t* p) {
  return static_cast<std::uint16_t>(p[0] | (p[1] << 8));
}

// The C-only formats: x from the pixel index, z from the 16-bit value.
std::size_t append_c16(const RangeFrameView& f, const RangeScaling& s, const LaserCalibration& c,
                       double line_step_mm, std::vector<analysis::Vec3>& out) {
  const std::size_t start = out.size();
  out.resize(start + std::size_t(f.width) * f.height);
  analysis::Vec3* dst = out.data() + start;
  std::size_t kept = 0;
  // An invalid value outside 0..65535 can never match a pixel.
  const bool check = s.c.invalid_flag && s.c.invalid_value >= 0.0 && s.c.invalid_value <= 65535.0;
  const auto invalid = static_cast<std::uint16_t>(check ? s.c.invalid_value : 0.0);
  const double ax = s.a.scale * s.unit_mm, bx = s.a.offset * s.unit_mm;
  const double az = s.c.scale * s.unit_mm, bz = s.c.offset * s.unit_mm;
  const std::uint8_t* src = f.data;
  for (std::uint32_t row = 0; row < f.height; ++row) {
    const double m = double(f.first_line + row) * line_step_mm;
    const analysis::Vec3 base = c.origin_mm + m * c.motion_axis;
    for (std::uint32_t i = 0; i < f.width; ++i, src += 2) {
      const std::uint16_t v = load_u16(src);
      dst[kept] = base + (double(i) * ax + bx) * c.x_axis + (double(v) * az + bz) * c.z_axis;
      kept += (check && v == invalid) ? 0 : 1;  // branch-free: overwritten by the next pixel
    }
  }
  out.resize(start + kept);
  return kept;
}

std::size_t append_abc32f(const RangeFrameView& f, const RangeScaling& s, const LaserCalibration& c,
                          double line_step_mm, std::vector<analysis::Vec3>& out) {
  const std::size_t start = out.size();
  out.resize(start + std::size_t(f.width) * f.height);
  analysis::Vec3* dst = out.data() + start;
  std::size_t kept = 0;
  const auto scaled = [&s](const CoordinateScale& k, float v) {
    return (double(v) * k.scale + k.offset) * s.unit_mm;
  };
  const std::uint8_t* src = f.data;
  for (std::uint32_t row = 0; row < f.height; ++row) {
    const double m = double(f.first_line + row) * line_step_mm;
    for (std::uint32_t i = 0; i < f.width; ++i, src += 12) {
      const float a = load_f32(src), b = load_f32(src + 4), cz = load_f32(src + 8);
      const bool missing = !std::isfinite(a) || !std::isfinite(b) || !std::isfinite(cz) ||
                           (s.c.invalid_flag && double(cz) == s.c.invalid_value);
      dst[kept] = c.origin_mm + scaled(s.a, a) * c.x_axis + scaled(s.c, cz) * c.z_axis +
                  (m + scaled(s.b, b)) * c.motion_axis;
      kept += missing ? 0 : 1;
    }
  }
  out.resize(start + kept);
  return kept;
}

}  // namespace

std::string to_string(RangeFormat format) {
  switch (format) {
    case RangeFormat::kMono16:
      return "Mono16";
    case RangeFormat::kCoord3dC16:
      return "Coord3D_C16";
    case RangeFormat::kCoord3dAbc32f:
      return "Coord3D_ABC32f";
  }
  return "";
}

std::size_t pixel_bytes(RangeFormat format) {
  return format == RangeFormat::kCoord3dAbc32f ? 12 : 2;
}

std::string validate(const RangeFrameView& f) {
  if (to_string(f.format).empty())
    return "pixel format 0x" + [&] {
      char hex[16];
      std::snprintf(hex, sizeof hex, "%08x", static_cast<unsigned>(f.format));
      return std::string(hex);
    }() + " is not a range format (Coord3D_C16, Coord3D_ABC32f, Mono16)";
  const std::size_t need = std::size_t(f.width) * f.height * pixel_bytes(f.format);
  if (f.data == nullptr || f.size < need)
    return "frame of " + std::to_string(f.size) + " bytes, " + std::to_string(f.width) + " x " +
           std::to_string(f.height) + " " + to_string(f.format) + " needs " + std::to_string(need);
  return "";
}

std::size_t append_range_lines(const RangeFrameView& frame, const RangeScaling& scaling,
                               const LaserCalibration& calibration, double line_step_mm,
                               std::vector<analysis::Vec3>& out) {
  if (frame.format == RangeFormat::kCoord3dAbc32f)
    return append_abc32f(frame, scaling, calibration, line_step_mm, out);
  return append_c16(frame, scaling, calibration, line_step_mm, out);
}

std::int64_t block_id_step(std::uint64_t previous, std::uint64_t current) {
  if (previous > 0xFFFF || current > 0xFFFF)
    return static_cast<std::int64_t>(current) - static_cast<std::int64_t>(previous);
  // On the ring 1..65535: the shorter way round, forward or back.
  constexpr std::int64_t kRing = 0xFFFF;
  std::int64_t step =
      (static_cast<std::int64_t>(current) - static_cast<std::int64_t>(previous)) % kRing;
  if (step > kRing / 2) step -= kRing;
  if (step < -kRing / 2) step += kRing;
  return step;
}

}  // namespace springscan::drivers::genicam
