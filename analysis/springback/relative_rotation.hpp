#pragma once
// The relative rotation between two local best fits (paper section 4): its axis is the
// eigenvector of R for the eigenvalue 1 and its angle follows from
// cos(alpha) = <w, R w> / (|w| |R w|) with w perpendicular to the axis.

#include "analysis/core/point_cloud.hpp"

namespace springscan::analysis {

/// A rotation as axis and angle, computed the paper's way.
struct AxisAngle {
  Vec3 axis = Vec3::UnitZ();  ///< unit; the rotation is right-handed about it
  double angle_deg = 0.0;     ///< in [0, 180]
  bool axis_defined = false;  ///< false for the identity (angle 0): any axis would do
};

/// Axis and angle of the rotation matrix R (orthonormal, det +1). The axis is the null vector
/// of R - I (the eigenvector of eigenvalue 1), taken as the largest cross product of two rows
/// of R - I, which stays well conditioned at 180 degrees; it is oriented so that the rotation
/// about it is positive. The angle uses the paper's cosine together with the matching sine
/// (atan2), so it is accurate near 0 and 180 degrees as well. At exactly 180 degrees both axis
/// orientations describe R; the one returned is either.
AxisAngle axis_angle_of(const Mat3& R);

/// The relative rotation of two local fits, paper section 4 / Figure 8. T_model_a and
/// T_model_b map the data subsets A and B onto the model. Returns the rotation of subset B
/// relative to subset A as found in the data, expressed in the model frame:
/// D = R_a * R_b^-1. If the data equal the model except that B is turned by alpha about v,
/// the result is (v, alpha). The paper's "last transformation" T_b * T_a^-1 has the inverse
/// rotation (the same angle, the axis reversed).
AxisAngle relative_rotation(const Transform& T_model_a, const Transform& T_model_b);

/// The rotation matrix D = R_a * R_b^-1 that relative_rotation() decomposes.
Mat3 relative_rotation_matrix(const Transform& T_model_a, const Transform& T_model_b);

}  // namespace springscan::analysis
