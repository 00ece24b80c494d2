#include "simulators/scan_pattern.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

namespace springscan::simulators {
namespace {

using analysis::Vec3;

// Noise, outliers and dropouts along the measuring direction of one reading; NaN = missing.
double disturb(double value, const NoiseSettings& noise, std::mt19937& rng) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  if (noise.missing_fraction > 0.0 && u(rng) < noise.missing_fraction)
    return std::numeric_limits<double>::quiet_NaN();
  if (noise.sigma_mm > 0.0) value += std::normal_distribution<double>(0.0, noise.sigma_mm)(rng);
  if (noise.outlier_fraction > 0.0 && u(rng) < noise.outlier_fraction)
    value += (2.0 * u(rng) - 1.0) * noise.outlier_mm;
  return value;
}

}  // namespace

namespace {

// One head: profiles in its own frame (calibration c).
std::vector<SimulatedProfile> head_profiles(const analysis::PointCloud& surface,
                                            const LaserPatternSettings& s,
                                            const NoiseSettings& noise, std::mt19937& rng) {
  std::vector<SimulatedProfile> profiles;
  const auto& c = s.calibration;
  const double m2 = c.motion_axis.squaredNorm();
  if (surface.empty() || m2 == 0.0 || s.step_mm <= 0.0 || s.points_per_profile < 1) return profiles;
  // The encoder and line coordinate of every surface point (§4.1 inverted).
  double e_min = std::numeric_limits<double>::infinity(), e_max = -e_min;
  double x_min = e_min, x_max = -e_min;
  for (const Vec3& q : surface.points) {
    const Vec3 d = q - c.origin_mm;
    const double e = d.dot(c.motion_axis) / m2;
    const double x = (d - e * c.motion_axis).dot(c.x_axis);
    e_min = std::min(e_min, e), e_max = std::max(e_max, e);
    x_min = std::min(x_min, x), x_max = std::max(x_max, x);
  }
  const auto count = static_cast<std::size_t>(std::floor((e_max - e_min) / s.step_mm)) + 1;
  const auto bins = static_cast<std::size_t>(std::min(s.points_per_profile, 4096));
  const double bin_w = std::max((x_max - x_min) / static_cast<double>(bins), 1e-9);
  // Per profile and bin: the sensor reading nearest to the sensor (smallest range z).
  std::vector<drivers::SensorPoint> grid(count * bins,
                                         {0.0f, std::numeric_limits<float>::quiet_NaN()});
  for (const Vec3& q : surface.points) {
    const Vec3 d = q - c.origin_mm;
    const double e = d.dot(c.motion_axis) / m2;
    const auto k = static_cast<std::size_t>(std::lround((e - e_min) / s.step_mm));
    if (k >= count) continue;
    const double e_k = e_min + static_cast<double>(k) * s.step_mm;
    if (std::abs(e - e_k) * std::sqrt(m2) > s.slice_half_thickness_mm) continue;
    const Vec3 local = d - e_k * c.motion_axis;
    const double x = local.dot(c.x_axis), z = local.dot(c.z_axis);
    const auto j = std::min(bins - 1, static_cast<std::size_t>((x - x_min) / bin_w));
    auto& cell = grid[k * bins + j];
    if (std::isnan(cell.z_mm) || z < cell.z_mm) cell = {float(x), float(z)};
  }
  profiles.resize(count);
  for (std::size_t k = 0; k < count; ++k) {
    profiles[k].encoder_mm = e_min + static_cast<double>(k) * s.step_mm;
    profiles[k].points.assign(grid.begin() + static_cast<std::ptrdiff_t>(k * bins),
                              grid.begin() + static_cast<std::ptrdiff_t>((k + 1) * bins));
    for (auto& p : profiles[k].points) {
      if (std::isnan(p.z_mm)) {
        p.x_mm = float(x_min + bin_w * (static_cast<double>(&p - profiles[k].points.data()) + 0.5));
        continue;
      }
      p.z_mm = float(disturb(p.z_mm, noise, rng));  // the laser measures range: noise along z
    }
  }
  return profiles;
}

// The head's calibration turned by `tilt_rad` about the motion axis (its laser plane stays the
// primary head's plane, so its readings convert exactly into the primary frame).
drivers::LaserCalibration tilted(const drivers::LaserCalibration& c, double tilt_rad) {
  const Eigen::AngleAxisd turn(tilt_rad, c.motion_axis.normalized());
  drivers::LaserCalibration head = c;
  head.x_axis = turn * c.x_axis;
  head.z_axis = turn * c.z_axis;
  return head;
}

// Re-expresses a tilted head's readings in the primary head's (x, z): same origin and plane.
void to_primary(std::vector<SimulatedProfile>& profiles, const drivers::LaserCalibration& head,
                const drivers::LaserCalibration& primary) {
  for (auto& profile : profiles)
    for (auto& p : profile.points) {
      if (std::isnan(p.z_mm)) continue;
      const Vec3 local = double(p.x_mm) * head.x_axis + double(p.z_mm) * head.z_axis;
      p = {float(local.dot(primary.x_axis)), float(local.dot(primary.z_axis))};
    }
}

}  // namespace

std::vector<SimulatedProfile> laser_profiles(const analysis::PointCloud& surface,
                                             const LaserPatternSettings& s,
                                             const NoiseSettings& noise, std::mt19937& rng) {
  if (s.head_tilt_deg == 0.0) return head_profiles(surface, s, noise, rng);
  std::vector<SimulatedProfile> all;
  constexpr double kRad = std::numbers::pi / 180.0;
  for (double sign : {1.0, -1.0}) {
    // The head measures from where it is; the device converts as if it were where it was
    // mounted, so a drifted second head's points come out turned by the drift.
    const double mounted = sign * s.head_tilt_deg;
    const double actual = mounted + (sign < 0.0 ? s.second_head_drift_deg : 0.0);
    LaserPatternSettings head = s;
    head.calibration = tilted(s.calibration, actual * kRad);
    auto profiles = head_profiles(surface, head, noise, rng);
    to_primary(profiles, tilted(s.calibration, mounted * kRad), s.calibration);
    all.insert(all.end(), std::make_move_iterator(profiles.begin()),
               std::make_move_iterator(profiles.end()));
  }
  return all;
}

std::vector<drivers::ProbeRecord> probe_grid(const analysis::PointCloud& surface,
                                             const ProbePatternSettings& s,
                                             const NoiseSettings& noise, std::mt19937& rng) {
  std::vector<drivers::ProbeRecord> records;
  if (surface.empty() || s.grid_step_mm <= 0.0 || s.direction.norm() == 0.0) return records;
  const Vec3 d = s.direction.normalized();
  // A basis (u, v) across the approach direction spans the grid.
  const Vec3 u = d.unitOrthogonal(), v = d.cross(u);
  double u0 = std::numeric_limits<double>::infinity(), v0 = u0, u1 = -u0, v1 = -u0;
  for (const Vec3& q : surface.points) {
    u0 = std::min(u0, q.dot(u)), u1 = std::max(u1, q.dot(u));
    v0 = std::min(v0, q.dot(v)), v1 = std::max(v1, q.dot(v));
  }
  const auto nu = static_cast<std::size_t>(std::floor((u1 - u0) / s.grid_step_mm)) + 1;
  const auto nv = static_cast<std::size_t>(std::floor((v1 - v0) / s.grid_step_mm)) + 1;
  // Per node: the surface point met first along d (smallest d-coordinate) within the capture
  // radius of the node's line.
  std::vector<std::int64_t> first(nu * nv, -1);
  for (std::size_t i = 0; i < surface.size(); ++i) {
    const Vec3& q = surface.points[i];
    const double a = (q.dot(u) - u0) / s.grid_step_mm, b = (q.dot(v) - v0) / s.grid_step_mm;
    const long iu = std::lround(a), iv = std::lround(b);
    if (iu < 0 || iv < 0 || iu >= long(nu) || iv >= long(nv)) continue;
    if (std::hypot(a - double(iu), b - double(iv)) * s.grid_step_mm > s.capture_radius_mm) continue;
    auto& best = first[static_cast<std::size_t>(iu) * nv + static_cast<std::size_t>(iv)];
    if (best < 0 || q.dot(d) < surface.points[static_cast<std::size_t>(best)].dot(d))
      best = static_cast<std::int64_t>(i);
  }
  const analysis::Transform T_machine_part = s.calibration.T_part_machine.inverse();
  const Vec3 d_machine = T_machine_part.linear() * d;
  for (const std::int64_t index : first) {
    if (index < 0) continue;
    const double along = disturb(0.0, noise, rng);  // contact error along the approach
    if (std::isnan(along)) continue;                // a missed touch
    const Vec3 contact = surface.points[static_cast<std::size_t>(index)] + along * d;
    // The stylus centre is one radius short of the contact, against the approach (§4.2).
    const Vec3 centre = T_machine_part * (contact - double(s.stylus_radius_mm) * d);
    drivers::ProbeRecord r;
    r.center_mm = {centre.x(), centre.y(), centre.z()};
    r.direction = {float(d_machine.x()), float(d_machine.y()), float(d_machine.z())};
    r.stylus_radius_mm = s.stylus_radius_mm;
    records.push_back(r);
  }
  return records;
}

}  // namespace springscan::simulators
