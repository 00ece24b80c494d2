#include "analysis/springback/relative_rotation.hpp"

#include <cmath>
#include <numbers>

namespace springscan::analysis {
namespace {

constexpr double kRadToDeg = 180.0 / std::numbers::pi;

// The null vector of the rank-2 matrix M = R - I: the cross product of two of its rows. The
// largest of the three products is the best conditioned (all vanish only for R = I).
Vec3 null_vector(const Mat3& M) {
  const Vec3 candidates[3] = {M.row(0).cross(M.row(1)), M.row(1).cross(M.row(2)),
                              M.row(2).cross(M.row(0))};
  Vec3 best = candidates[0];
  for (const Vec3& c : candidates)
    if (c.squaredNorm() > best.squaredNorm()) best = c;
  return best;
}

// A unit vector perpendicular to `axis`: the cross product with the coordinate axis least
// aligned with it.
Vec3 perpendicular(const Vec3& axis) {
  Eigen::Index least = 0;
  axis.cwiseAbs().minCoeff(&least);
  return axis.cross(Vec3::Unit(least)).normalized();
}

}  // namespace

AxisAngle axis_angle_of(const Mat3& R) {
  AxisAngle result;
  const Vec3 v = null_vector(R - Mat3::Identity());
  // |v| is of order angle^2: below this the rotation is the identity to rounding.
  if (!(v.norm() > 1e-28)) return result;
  result.axis = v.normalized();
  result.axis_defined = true;
  // Paper section 4: cos(alpha) = <w, Rw> / (|w| |Rw|) with w perpendicular to the axis; the
  // sine <axis, w x Rw> / (|w| |Rw|) fixes the sign and keeps atan2 accurate near 0 and 180.
  const Vec3 w = perpendicular(result.axis);
  const Vec3 Rw = R * w;
  const double scale = w.norm() * Rw.norm();
  double cos_alpha = w.dot(Rw) / scale;
  double sin_alpha = result.axis.dot(w.cross(Rw)) / scale;
  if (sin_alpha < 0.0) {  // orient the axis so that the rotation about it is positive
    result.axis = -result.axis;
    sin_alpha = -sin_alpha;
  }
  result.angle_deg = std::atan2(sin_alpha, cos_alpha) * kRadToDeg;
  return result;
}

Mat3 relative_rotation_matrix(const Transform& T_model_a, const Transform& T_model_b) {
  return T_model_a.linear() * T_model_b.linear().transpose();
}

AxisAngle relative_rotation(const Transform& T_model_a, const Transform& T_model_b) {
  return axis_angle_of(relative_rotation_matrix(T_model_a, T_model_b));
}

}  // namespace springscan::analysis
