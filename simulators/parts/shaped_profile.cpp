#include "simulators/parts/shaped_profile.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <string>

namespace springscan::parts {
namespace {

using Vec2 = Eigen::Vector2d;
constexpr double kDeg = std::numbers::pi / 180.0;

Vec2 heading(double angle_rad) { return {std::cos(angle_rad), std::sin(angle_rad)}; }
Vec2 left_of(const Vec2& d) { return {-d.y(), d.x()}; }
double value_or_zero(const std::vector<double>& v, std::size_t i) {
  return i < v.size() ? v[i] : 0.0;
}

// Flange i's length as produced.
double flange_length(const ProfileSpec& nominal, const ProfileShape& shape, std::size_t i) {
  return nominal.flange_lengths_mm[i] + value_or_zero(shape.length_change_mm, i);
}

// Signed sweep (radians, left positive) of flange i's curl: its length over its radius.
double curl_sweep_rad(const ProfileSpec& nominal, const ProfileShape& shape, std::size_t i) {
  const double rho = value_or_zero(shape.curl_radius_mm, i);
  return rho == 0.0 ? 0.0 : flange_length(nominal, shape, i) / rho;
}

// Signed turn of bend i at y (radians): the nominal turn less the springback there, less half
// the curl sweep of each neighbouring flange (so curled flanges keep their chords' direction).
double signed_turn_rad(const ProfileSpec& nominal, const ProfileShape& shape, std::size_t i,
                       double y) {
  const double a = nominal.bend_angles_deg[i];
  const double springback = value_or_zero(shape.springback_deg, i) +
                            value_or_zero(shape.springback_gradient_deg_per_100mm, i) *
                                (y - 0.5 * nominal.width_mm) / 100.0;
  const double sign = a > 0.0 ? 1.0 : -1.0;
  return (a - sign * springback) * kDeg -
         0.5 * (curl_sweep_rad(nominal, shape, i) + curl_sweep_rad(nominal, shape, i + 1));
}

// The middle of the nominal path by arc length: the twist's pivot, so a twisted section moves
// as little as it can.
Vec2 path_middle(const ProfileSpec& nominal) {
  const auto path = profile_path(nominal);
  double total = 0.0;
  for (const auto& e : path) total += e.length_mm();
  double left = 0.5 * total;
  for (const auto& e : path) {
    if (left <= e.length_mm()) {
      if (e.kind == ProfileElement::Kind::kLine)
        return e.start + left / e.length_mm() * (e.end - e.start);
      const double sign = e.sweep_rad > 0.0 ? 1.0 : -1.0;
      return e.center + e.radius_mm * heading(e.start_angle_rad + sign * left / e.radius_mm);
    }
    left -= e.length_mm();
  }
  return path.back().end;
}

// An element from `position` heading `direction`: a line when sweep is 0, else an arc of
// `radius` turning by `sweep` (left positive). Advances position and direction.
ProfileElement advance(Vec2& position, double& direction, double length, double radius,
                       double sweep) {
  ProfileElement e;
  e.start = position;
  if (sweep == 0.0) {
    e.kind = ProfileElement::Kind::kLine;
    e.end = position + length * heading(direction);
  } else {
    e.kind = ProfileElement::Kind::kArc;
    const double side = sweep > 0.0 ? 1.0 : -1.0;
    e.center = position + side * radius * left_of(heading(direction));
    e.radius_mm = radius;
    const Vec2 from_center = position - e.center;
    e.start_angle_rad = std::atan2(from_center.y(), from_center.x());
    e.sweep_rad = sweep;
    e.end = e.center + radius * heading(e.start_angle_rad + sweep);
  }
  position = e.end;
  direction += sweep;
  return e;
}

std::string check(const ProfileSpec& nominal, const ProfileShape& shape) {
  if (!is_valid(nominal)) return "invalid nominal ProfileSpec";
  const std::size_t n = nominal.flange_lengths_mm.size(), bends = n - 1;
  const auto sized = [](const std::vector<double>& v, std::size_t want) {
    return v.empty() || v.size() == want;
  };
  if (!sized(shape.springback_deg, bends) ||
      !sized(shape.springback_gradient_deg_per_100mm, bends) || !sized(shape.curl_radius_mm, n) ||
      !sized(shape.length_change_mm, n) || !sized(shape.width_change_mm, n))
    return "springback, gradient, curl, length and width change need one value per bend, bend, "
           "flange, flange and flange";
  for (double w : shape.width_change_mm)
    if (!(nominal.width_mm + w > 0.0)) return "a width change leaves no flange";
  for (std::size_t i = 0; i < n; ++i)
    if (!(flange_length(nominal, shape, i) > 0.0))
      return "flange " + std::to_string(i) + ": length change leaves no flange";
  for (std::size_t i = 0; i < n; ++i)
    if (std::abs(curl_sweep_rad(nominal, shape, i)) >= std::numbers::pi)
      return "flange " + std::to_string(i) + ": curl sweeps half a turn or more";
  for (std::size_t i = 0; i < bends; ++i) {
    for (double y : {0.0, nominal.width_mm}) {
      const double turn = signed_turn_rad(nominal, shape, i, y);
      if (!(turn * nominal.bend_angles_deg[i] > 0.0 && std::abs(turn) < std::numbers::pi))
        return "bend " + std::to_string(i) + ": produced turn " + std::to_string(turn / kDeg) +
               " deg at y " + std::to_string(y) + " changes sign or reaches 180";
    }
  }
  return {};
}

// The section at y without checks (shaped_section checks once).
void build_section(const ProfileSpec& nominal, const ProfileShape& shape, const Vec2& pivot,
                   double y, std::vector<ProfileElement>& path) {
  path.clear();
  const double twist = -shape.twist_deg_per_100mm * kDeg * (y - 0.5 * nominal.width_mm) / 100.0;
  // Right-handed about +y turns the heading clockwise in (x, z): the start point turns with it.
  const Eigen::Rotation2Dd turn(twist);
  Vec2 position = pivot + turn * (Vec2::Zero() - pivot);
  // The first flange starts turned back by half its curl, so its chord keeps its direction too.
  double direction = twist - 0.5 * curl_sweep_rad(nominal, shape, 0);
  const std::size_t n = nominal.flange_lengths_mm.size();
  for (std::size_t i = 0; i < n; ++i) {
    const double sweep = curl_sweep_rad(nominal, shape, i);
    const double rho = std::abs(value_or_zero(shape.curl_radius_mm, i));
    ProfileElement flange =
        advance(position, direction, flange_length(nominal, shape, i), rho, sweep);
    flange.flange_index = static_cast<int>(i);
    path.push_back(flange);
    if (i + 1 == n) break;
    ProfileElement bend = advance(position, direction, 0.0, nominal.bend_radii_mm[i],
                                  signed_turn_rad(nominal, shape, i, y));
    bend.bend_index = static_cast<int>(i);
    path.push_back(bend);
  }
}

struct PathPoint {
  Vec2 position;
  Vec2 normal;  // left of the path: the reference-side normal
};

PathPoint point_at(const ProfileElement& e, double t) {
  if (e.kind == ProfileElement::Kind::kLine) {
    const Vec2 tangent = (e.end - e.start).normalized();
    return {e.start + t * tangent, left_of(tangent)};
  }
  const double turn = e.sweep_rad > 0.0 ? 1.0 : -1.0;
  const Vec2 radial = heading(e.start_angle_rad + turn * t / e.radius_mm);
  return {e.center + e.radius_mm * radial, -turn * radial};
}

}  // namespace

Expected<std::vector<ProfileElement>> shaped_section(const ProfileSpec& nominal,
                                                     const ProfileShape& shape, double y_mm) {
  if (const std::string bad = check(nominal, shape); !bad.empty())
    return fail("shaped_section: " + bad);
  std::vector<ProfileElement> path;
  build_section(nominal, shape, path_middle(nominal), y_mm, path);
  return path;
}

double shaped_bend_angle_deg(const ProfileSpec& nominal, const ProfileShape& shape, int bend,
                             double y_mm) {
  return std::abs(signed_turn_rad(nominal, shape, static_cast<std::size_t>(bend), y_mm)) / kDeg;
}

double shaped_flange_twist_deg_per_100mm(const ProfileSpec& nominal, const ProfileShape& shape,
                                         int flange) {
  // A flange's heading at y is the section's turn plus every turn before it; a heading that
  // grows along +y turns the normal left-handed about +y (sheet_profile.hpp frame).
  double twist = shape.twist_deg_per_100mm;
  for (std::size_t i = 0; i < static_cast<std::size_t>(flange); ++i) {
    const double sign = nominal.bend_angles_deg[i] > 0.0 ? 1.0 : -1.0;
    twist += sign * value_or_zero(shape.springback_gradient_deg_per_100mm, i);
  }
  return twist;
}

Expected<PointCloud> simulate_shaped_scan(const ProfileSpec& nominal, const ProfileShape& shape,
                                          const ScanSimulationSettings& settings) {
  if (const std::string bad = check(nominal, shape); !bad.empty())
    return fail("simulate_shaped_scan: " + bad);
  if (settings.point_count < 1 || settings.point_count > 50'000'000)
    return fail("simulate_shaped_scan: point_count " + std::to_string(settings.point_count) +
                " outside [1, 50000000]");
  if (settings.missing_fraction != 0.0 || !(settings.noise_sigma_mm >= 0.0) ||
      !(settings.outlier_fraction >= 0.0 && settings.outlier_fraction <= 0.5))
    return fail(
        "simulate_shaped_scan: missing_fraction must be 0, noise >= 0, outliers in [0, 0.5]");
  const Vec2 pivot = path_middle(nominal);
  std::mt19937_64 rng(settings.seed);
  // Uniform over the widest flange; a point beyond its own element's side edge is drawn again.
  double widest = 0.0;
  for (double w : shape.width_change_mm) widest = std::max(widest, w);
  const auto side_edge = [&](const ProfileElement& e) {
    return nominal.width_mm +
           (e.flange_index >= 0
                ? value_or_zero(shape.width_change_mm, static_cast<std::size_t>(e.flange_index))
                : 0.0);
  };
  std::uniform_real_distribution<double> uy(0.0, nominal.width_mm + widest), unit(0.0, 1.0);
  std::uniform_real_distribution<double> outlier(-settings.outlier_max_mm, settings.outlier_max_mm);
  std::normal_distribution<double> noise(0.0, std::max(settings.noise_sigma_mm, 1e-300));
  const bool noisy = settings.noise_sigma_mm > 0.0;
  PointCloud cloud;
  const auto count = static_cast<std::size_t>(settings.point_count);
  cloud.points.reserve(count);
  if (settings.with_normals) cloud.normals.reserve(count);
  std::vector<ProfileElement> path;
  while (cloud.points.size() < count) {
    const double y = uy(rng);
    build_section(nominal, shape, pivot, y, path);
    double total = 0.0;
    for (const auto& e : path) total += e.length_mm();
    double s = unit(rng) * total;
    std::size_t k = 0;
    while (k + 1 < path.size() && s > path[k].length_mm()) s -= path[k++].length_mm();
    if (y > side_edge(path[k])) continue;
    const PathPoint p = point_at(path[k], std::clamp(s, 0.0, path[k].length_mm()));
    const Vec3 normal(p.normal.x(), 0.0, p.normal.y());
    const bool is_outlier = unit(rng) < settings.outlier_fraction;
    const double offset = is_outlier ? outlier(rng) : (noisy ? noise(rng) : 0.0);
    cloud.points.push_back(settings.T_scan_part * (profile_to_3d(p.position, y) + offset * normal));
    if (settings.with_normals) cloud.normals.push_back(settings.T_scan_part.linear() * normal);
  }
  return cloud;
}

}  // namespace springscan::parts
