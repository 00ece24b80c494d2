#pragma once
// Head calibration results (analysis/registration/calibration.hpp) -> the messages of
// `springscan calibrate`: the record (HeadCalibration) and the driver's LaserCalibration
// (STYLE.md §1: only *_proto.cpp files touch proto types).

#include <string>

#include "analysis/registration/calibration.hpp"
#include "proto/springscan.pb.h"

namespace springscan::analysis {

/// The record of one head: transform (row-major 4x4), scale, residuals, uncertainty.
void to_proto(const HeadCalibration& head, const std::string& name, v1::HeadCalibration* out);

/// The laser line driver's calibration for a head whose raw frame is (x, z range, encoder):
/// origin = t, x_axis = R e_x, z_axis = R e_y, motion_axis = k R e_z, so that the driver's
/// p = origin + x x_axis + z z_axis + encoder motion_axis is T_station_head S(k) (x, z, encoder).
void to_laser_calibration(const HeadCalibration& head, v1::LaserCalibration* out);

}  // namespace springscan::analysis
