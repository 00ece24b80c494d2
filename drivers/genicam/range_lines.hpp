#pragma once
// GenICam range lines to part coordinates (docs/device-protocol.md, "GenICam 3D line
// profilers"): the hot loop of a GenICam acquisition, free of Aravis, I/O and allocation per
// point, so that tests and bench/bench_drivers.cpp drive it on plain byte arrays.
//
// A frame holds `height` lines of `width` pixels; pixel i of a line is the SFNC coordinate
// C (range) for Coord3D_C16 and Mono16, or the triple (A, B, C) for Coord3D_ABC32f. With the
// camera's Scan3dCoordinateScale/Offset per coordinate and Scan3dDistanceUnit:
//   x = (A * scale_a + offset_a) * unit_mm, A = i for the C-only formats
//   z = (C * scale_c + offset_c) * unit_mm
//   m = line * line_step_mm (+ (B * scale_b + offset_b) * unit_mm for ABC)
// and the point is the laser head's p = origin + x * x_axis + z * z_axis + m * motion_axis.

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "analysis/core/point_cloud.hpp"
#include "drivers/conversion.hpp"

namespace springscan::drivers::genicam {

/// The range pixel formats the driver reads (PFNC names; values as on the wire).
enum class RangeFormat : std::uint32_t {
  kMono16 = 0x01100007,         ///< range as an unsigned 16-bit "image"
  kCoord3dC16 = 0x011000B8,     ///< SFNC Coord3D_C16: C only, unsigned 16 bit
  kCoord3dAbc32f = 0x026000C0,  ///< SFNC Coord3D_ABC32f: A, B, C as little-endian floats
};

/// The PFNC name ("Coord3D_C16"), or "" for a value that is not a RangeFormat.
std::string to_string(RangeFormat format);
/// Bytes per pixel of `format`.
std::size_t pixel_bytes(RangeFormat format);

/// The camera's Scan3d scaling of one coordinate (SFNC Scan3dCoordinateSelector).
struct CoordinateScale {
  double scale = 1.0;          ///< Scan3dCoordinateScale
  double offset = 0.0;         ///< Scan3dCoordinateOffset
  bool invalid_flag = false;   ///< Scan3dInvalidDataFlag: invalid_value marks a missing pixel
  double invalid_value = 0.0;  ///< Scan3dInvalidDataValue (raw, before scale and offset)
};

/// How raw pixels become millimetres in the sensor's profile plane.
struct RangeScaling {
  CoordinateScale a;     ///< along the line (the pixel index for the C-only formats)
  CoordinateScale b;     ///< along the motion (ABC only; 0 for a profiler)
  CoordinateScale c;     ///< range
  double unit_mm = 1.0;  ///< Scan3dDistanceUnit in mm (1 for Millimeter, 25.4 for Inch)
};

/// One received frame, as bytes (not owned).
struct RangeFrameView {
  RangeFormat format = RangeFormat::kCoord3dC16;
  const std::uint8_t* data = nullptr;
  std::size_t size = 0;  ///< bytes at data
  std::uint32_t width = 0;
  std::uint32_t height = 0;
  std::int64_t first_line = 0;  ///< the scan's line index of row 0 (lost frames leave gaps)
};

/// A readable reason when `frame` cannot be converted (size, format), or "".
std::string validate(const RangeFrameView& frame);

/// Appends the frame's valid points in part coordinates and returns how many; pixels equal to
/// an active invalid value, and non-finite ones, are dropped. `frame` must pass validate().
std::size_t append_range_lines(const RangeFrameView& frame, const RangeScaling& scaling,
                               const LaserCalibration& calibration, double line_step_mm,
                               std::vector<analysis::Vec3>& out);

/// How many frames `current` comes after `previous` (1: the next one; 3: two lost between;
/// negative: an earlier frame arriving late). GigE Vision's 16-bit block ids run 1..65535 and
/// skip 0 when they wrap; USB3 Vision's are 64-bit.
std::int64_t block_id_step(std::uint64_t previous, std::uint64_t current);

}  // namespace springscan::drivers::genicam
