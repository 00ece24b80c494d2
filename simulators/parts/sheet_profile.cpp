#include "simulators/parts/sheet_profile.hpp"

#include <cmath>
#include <numbers>

namespace springscan::parts {
namespace {

constexpr double kDegToRad = std::numbers::pi / 180.0;

Eigen::Vector2d heading(double angle_rad) { return {std::cos(angle_rad), std::sin(angle_rad)}; }
Eigen::Vector2d left_of(const Eigen::Vector2d& d) { return {-d.y(), d.x()}; }

}  // namespace

double ProfileElement::length_mm() const {
  return kind == Kind::kLine ? (end - start).norm() : radius_mm * std::abs(sweep_rad);
}

bool is_valid(const ProfileSpec& spec) {
  const std::size_t n = spec.flange_lengths_mm.size();
  if (n == 0 || spec.bend_angles_deg.size() + 1 != n || spec.bend_radii_mm.size() + 1 != n)
    return false;
  if (!(spec.width_mm > 0.0) || !(spec.thickness_mm >= 0.0)) return false;
  for (double length : spec.flange_lengths_mm)
    if (!(length > 0.0)) return false;
  for (std::size_t i = 0; i + 1 < n; ++i) {
    const double a = spec.bend_angles_deg[i];
    if (!(std::abs(a) > 0.0 && std::abs(a) < 180.0)) return false;
    if (!(spec.bend_radii_mm[i] > 0.0)) return false;
    // A right turn puts the far side of the sheet on the inside of the bend.
    if (a < 0.0 && spec.thickness_mm >= spec.bend_radii_mm[i]) return false;
  }
  return true;
}

std::vector<ProfileElement> profile_path(const ProfileSpec& spec) {
  std::vector<ProfileElement> path;
  Eigen::Vector2d position = Eigen::Vector2d::Zero();
  double direction = 0.0;  // heading angle of the path, radians from +x towards +z
  const std::size_t n = spec.flange_lengths_mm.size();
  for (std::size_t i = 0; i < n; ++i) {
    ProfileElement line;
    line.kind = ProfileElement::Kind::kLine;
    line.start = position;
    line.end = position + spec.flange_lengths_mm[i] * heading(direction);
    line.flange_index = static_cast<int>(i);
    path.push_back(line);
    position = line.end;
    if (i + 1 == n) break;

    const double turn = spec.bend_angles_deg[i] * kDegToRad;
    const double r = spec.bend_radii_mm[i];
    const double side = turn > 0.0 ? 1.0 : -1.0;  // the centre lies on the side we turn to
    ProfileElement arc;
    arc.kind = ProfileElement::Kind::kArc;
    arc.start = position;
    arc.center = position + side * r * left_of(heading(direction));
    arc.radius_mm = r;
    const Eigen::Vector2d from_center = position - arc.center;
    arc.start_angle_rad = std::atan2(from_center.y(), from_center.x());
    arc.sweep_rad = turn;
    arc.end = arc.center + r * heading(arc.start_angle_rad + turn);
    arc.bend_index = static_cast<int>(i);
    path.push_back(arc);
    position = arc.end;
    direction += turn;
  }
  return path;
}

ProfileSpec l_profile(double leg_a_mm, double leg_b_mm, double angle_deg, double radius_mm) {
  return {{leg_a_mm, leg_b_mm}, {angle_deg}, {radius_mm}};
}

ProfileSpec u_profile(double flange_mm, double web_mm, double angle_deg, double radius_mm) {
  return {{flange_mm, web_mm, flange_mm}, {angle_deg, angle_deg}, {radius_mm, radius_mm}};
}

ProfileSpec hat_profile(double brim_mm, double wall_mm, double top_mm, double angle_deg,
                        double radius_mm) {
  return {{brim_mm, wall_mm, top_mm, wall_mm, brim_mm},
          {angle_deg, -angle_deg, -angle_deg, angle_deg},
          {radius_mm, radius_mm, radius_mm, radius_mm}};
}

ProfileSpec z_profile(double flange_mm, double web_mm, double angle_deg, double radius_mm) {
  return {{flange_mm, web_mm, flange_mm}, {angle_deg, -angle_deg}, {radius_mm, radius_mm}};
}

}  // namespace springscan::parts
