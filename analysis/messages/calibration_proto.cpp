#include "analysis/messages/calibration_proto.hpp"

#include "analysis/messages/fit_proto.hpp"

namespace springscan::analysis {
namespace {

void vec(const Vec3& v, v1::Vec3* out) {
  out->set_x(v.x());
  out->set_y(v.y());
  out->set_z(v.z());
}

}  // namespace

void to_proto(const HeadCalibration& head, const std::string& name, v1::HeadCalibration* out) {
  out->set_name(name);
  transform_to_proto(head.T_station_head, out->mutable_transform());
  out->set_motion_scale(head.motion_scale);
  out->set_rms_mm(head.rms_mm);
  out->set_p95_mm(head.p95_mm);
  out->set_points(static_cast<std::int64_t>(head.points));
  out->set_fitted_points(static_cast<std::int64_t>(head.fitted_points));
  out->set_inliers(static_cast<std::int64_t>(head.inliers));
  vec(head.centre, out->mutable_centre());
  vec(head.rotation_sigma_deg, out->mutable_uncertainty_rotation_deg());
  vec(head.translation_sigma_mm, out->mutable_uncertainty_translation_mm());
  out->set_uncertainty_motion_scale(head.motion_scale_sigma);
  out->set_weakest_direction_ratio(head.weakest_direction_ratio);
}

void to_laser_calibration(const HeadCalibration& head, v1::LaserCalibration* out) {
  const Mat3 R = head.T_station_head.linear();
  vec(head.T_station_head.translation(), out->mutable_origin_mm());
  vec(R.col(0), out->mutable_x_axis());
  vec(R.col(1), out->mutable_z_axis());
  vec(head.motion_scale * R.col(2), out->mutable_motion_axis());
}

}  // namespace springscan::analysis
