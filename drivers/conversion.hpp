#pragma once
// Data frames to part coordinates (docs/device-protocol.md §4.1, §4.2): the hot loops of an
// acquisition, kept free of I/O and allocation per point so that bench/bench_drivers.cpp can
// measure them alone.

#include <cstddef>
#include <vector>

#include "analysis/core/point_cloud.hpp"
#include "drivers/messages.hpp"

namespace springscan::drivers {

/// Where the laser's profile plane lies in the part frame (§4.1):
/// p = origin + x * x_axis + z * z_axis + encoder * motion_axis.
struct LaserCalibration {
  analysis::Vec3 origin_mm{0.0, 0.0, 200.0};  ///< sensor origin at encoder 0, part frame, mm
  analysis::Vec3 x_axis{1.0, 0.0, 0.0};       ///< sensor x (along the line), unit, part frame
  analysis::Vec3 z_axis{0.0, 0.0, -1.0};      ///< sensor z (range, away from the sensor), unit
  analysis::Vec3 motion_axis{0.0, 1.0, 0.0};  ///< part-frame travel per mm of encoder
};

/// The tactile probe's machine frame in the part frame (§4.2).
struct ProbeCalibration {
  analysis::Transform T_part_machine = analysis::Transform::Identity();  ///< machine to part
};

/// A readable reason when the calibration cannot be used (zero or non-orthogonal axes), or "".
std::string validate(const LaserCalibration& calibration);

/// Appends the profile's valid points (z not NaN) in part coordinates; returns how many.
std::size_t append_laser_profile(const LaserProfileView& profile,
                                 const LaserCalibration& calibration,
                                 std::vector<analysis::Vec3>& out);

/// Appends the touched surface points (stylus centre + radius * direction, §4.2) in part
/// coordinates and, when `normals` is not null, the surface normal estimate -direction.
std::size_t append_probe_batch(const ProbeBatchView& batch, const ProbeCalibration& calibration,
                               std::vector<analysis::Vec3>& out,
                               std::vector<analysis::Vec3>* normals);

}  // namespace springscan::drivers
