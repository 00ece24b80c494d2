#include "simulators/parts/sheet_part.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <random>
#include <string>

namespace springscan::parts {
namespace {

using Vec2 = Eigen::Vector2d;
constexpr double kTwoPi = 2.0 * std::numbers::pi;

Vec2 left_of(const Vec2& d) { return {-d.y(), d.x()}; }
Vec3 to_3d_direction(const Vec2& xz) { return {xz.x(), 0.0, xz.y()}; }

// A point of an element at arc length t in [0, length] and the reference-side normal there
// (left of the path, sheet_profile.hpp convention).
struct PathPoint {
  Vec2 position;
  Vec2 normal;
};

PathPoint point_at(const ProfileElement& e, double t) {
  if (e.kind == ProfileElement::Kind::kLine) {
    const Vec2 tangent = (e.end - e.start).normalized();
    return {e.start + t * tangent, left_of(tangent)};
  }
  const double turn = e.sweep_rad > 0.0 ? 1.0 : -1.0;
  const double phi = e.start_angle_rad + turn * t / e.radius_mm;
  const Vec2 radial(std::cos(phi), std::sin(phi));
  // The tangent is turn * (-sin, cos); its left side is -turn * radial.
  return {e.center + e.radius_mm * radial, -turn * radial};
}

// The closest point of one element to q, in the profile plane.
PathPoint closest_on(const ProfileElement& e, const Vec2& q) {
  if (e.kind == ProfileElement::Kind::kLine) {
    const double length = (e.end - e.start).norm();
    const double t = std::clamp((q - e.start).dot(e.end - e.start) / length, 0.0, length);
    return point_at(e, t);
  }
  const double turn = e.sweep_rad > 0.0 ? 1.0 : -1.0;
  const Vec2 d = q - e.center;
  const double phi = std::atan2(d.y(), d.x());
  // Angle travelled from the start in the direction of the sweep, in [0, 2 pi).
  double u = std::fmod(turn * (phi - e.start_angle_rad), kTwoPi);
  if (u < 0.0) u += kTwoPi;
  const double sweep = std::abs(e.sweep_rad);
  if (u <= sweep) return point_at(e, u * e.radius_mm);
  const PathPoint a = point_at(e, 0.0);
  const PathPoint b = point_at(e, sweep * e.radius_mm);
  return (q - a.position).squaredNorm() <= (q - b.position).squaredNorm() ? a : b;
}

class ProfileSurfaceDistance final : public SurfaceDistance {
 public:
  explicit ProfileSurfaceDistance(const ProfileSpec& spec)
      : path_(profile_path(spec)), width_mm_(spec.width_mm) {}

  SurfaceHit closest(const Vec3& query) const override {
    const Vec2 q(query.x(), query.z());
    SurfaceHit hit;
    double best = std::numeric_limits<double>::infinity();
    PathPoint best_point{};
    for (std::size_t i = 0; i < path_.size(); ++i) {
      const PathPoint p = closest_on(path_[i], q);
      const double d2 = (q - p.position).squaredNorm();
      if (d2 < best) {
        best = d2;
        best_point = p;
        hit.face_id = profile_face_id(static_cast<int>(i));
      }
    }
    hit.foot = profile_to_3d(best_point.position, std::clamp(query.y(), 0.0, width_mm_));
    hit.normal = to_3d_direction(best_point.normal);
    const Vec3 offset = query - hit.foot;
    hit.signed_distance_mm = offset.dot(hit.normal) < 0.0 ? -offset.norm() : offset.norm();
    return hit;
  }

 private:
  std::vector<ProfileElement> path_;
  double width_mm_;
};

PartSegmentation segmentation_of(const ProfileSpec& spec, const std::vector<ProfileElement>& path) {
  PartSegmentation seg;
  const double mid_y = 0.5 * spec.width_mm;
  for (std::size_t i = 0; i < path.size(); ++i) {
    const ProfileElement& e = path[i];
    const int face = profile_face_id(static_cast<int>(i));
    if (e.kind == ProfileElement::Kind::kLine) {
      const PathPoint mid = point_at(e, 0.5 * e.length_mm());
      seg.flanges.push_back({e.flange_index,
                             {face},
                             profile_to_3d(mid.position, mid_y),
                             to_3d_direction(mid.normal),
                             e.length_mm() * spec.width_mm});
      continue;
    }
    Bend bend;
    bend.id = e.bend_index;
    bend.face_ids = {face};
    bend.axis_point = profile_to_3d(e.center, mid_y);
    // A left turn (sweep > 0) takes +x towards +z: a positive rotation about -y.
    bend.axis_direction = Vec3(0.0, e.sweep_rad > 0.0 ? -1.0 : 1.0, 0.0);
    // The reference side is the inner side of a left turn; of a right turn, the far side is.
    bend.radius_mm = e.sweep_rad > 0.0 ? e.radius_mm : e.radius_mm - spec.thickness_mm;
    bend.nominal_angle_deg = std::abs(spec.bend_angles_deg[static_cast<std::size_t>(e.bend_index)]);
    bend.flange_a = e.bend_index;
    bend.flange_b = e.bend_index + 1;
    seg.bends.push_back(bend);
  }
  return seg;
}

double total_length(const std::vector<ProfileElement>& path) {
  double sum = 0.0;
  for (const auto& e : path) sum += e.length_mm();
  return sum;
}

// A hole in the (arc length, width) parameter rectangle.
struct Patch {
  double s0, s1, y0, y1;
  bool contains(double s, double y) const { return s >= s0 && s <= s1 && y >= y0 && y <= y1; }
};

std::vector<Patch> random_patches(double length, double width, const ScanSimulationSettings& st,
                                  std::mt19937_64& rng) {
  std::vector<Patch> patches;
  if (st.missing_fraction <= 0.0) return patches;
  const double area = st.missing_fraction * length * width / st.missing_patches;
  const double side_y = std::min(width, std::sqrt(area));
  const double side_s = std::min(length, area / side_y);
  std::uniform_real_distribution<double> us(0.0, length - side_s), uy(0.0, width - side_y);
  for (int i = 0; i < st.missing_patches; ++i) {
    const double s0 = us(rng), y0 = uy(rng);
    patches.push_back({s0, s0 + side_s, y0, y0 + side_y});
  }
  return patches;
}

std::string check_settings(const ScanSimulationSettings& st) {
  if (st.point_count < 1 || st.point_count > 50'000'000)
    return "point_count " + std::to_string(st.point_count) + " outside [1, 50000000]";
  if (!(st.noise_sigma_mm >= 0.0 && st.noise_sigma_mm < 100.0))
    return "noise_sigma_mm " + std::to_string(st.noise_sigma_mm) + " outside [0, 100)";
  if (!(st.outlier_fraction >= 0.0 && st.outlier_fraction <= 0.5))
    return "outlier_fraction " + std::to_string(st.outlier_fraction) + " outside [0, 0.5]";
  if (!(st.outlier_max_mm >= 0.0 && st.outlier_max_mm < 1000.0))
    return "outlier_max_mm " + std::to_string(st.outlier_max_mm) + " outside [0, 1000)";
  if (!(st.missing_fraction >= 0.0 && st.missing_fraction <= 0.8))
    return "missing_fraction " + std::to_string(st.missing_fraction) + " outside [0, 0.8]";
  if (st.missing_patches < 1 || st.missing_patches > 1000)
    return "missing_patches " + std::to_string(st.missing_patches) + " outside [1, 1000]";
  return {};
}

}  // namespace

std::shared_ptr<const SurfaceDistance> profile_surface_distance(const ProfileSpec& spec) {
  return std::make_shared<ProfileSurfaceDistance>(spec);
}

Expected<PartModel> profile_part_model(const ProfileSpec& spec,
                                       const SheetSamplingSettings& settings) {
  if (!is_valid(spec)) return fail("profile_part_model: invalid ProfileSpec");
  if (settings.sample_count < 1 || settings.sample_count > 50'000'000)
    return fail("profile_part_model: sample_count " + std::to_string(settings.sample_count) +
                " outside [1, 50000000]");
  const auto path = profile_path(spec);
  const double length = total_length(path);
  const double spacing = std::sqrt(length * spec.width_mm / settings.sample_count);
  const auto cells = [spacing](double extent) {
    return std::max<std::size_t>(1, static_cast<std::size_t>(std::lround(extent / spacing)));
  };
  const std::size_t across = cells(spec.width_mm);
  PartModel model;
  model.samples.points.reserve(static_cast<std::size_t>(settings.sample_count) * 11 / 10 + 64);
  for (std::size_t i = 0; i < path.size(); ++i) {
    const std::size_t along = cells(path[i].length_mm());
    for (std::size_t a = 0; a < along; ++a) {
      const PathPoint p = point_at(path[i], (a + 0.5) / along * path[i].length_mm());
      for (std::size_t c = 0; c < across; ++c) {
        model.samples.points.push_back(
            profile_to_3d(p.position, (c + 0.5) / across * spec.width_mm));
        model.samples.normals.push_back(to_3d_direction(p.normal));
        model.samples.face_ids.push_back(profile_face_id(static_cast<int>(i)));
      }
    }
  }
  model.segmentation = segmentation_of(spec, path);
  model.face_count = static_cast<int>(path.size());
  model.distance = profile_surface_distance(spec);
  return model;
}

Expected<ProfileSpec> produced_profile(const ProfileSpec& nominal,
                                       const std::vector<double>& springback_deg) {
  if (!is_valid(nominal)) return fail("produced_profile: invalid nominal ProfileSpec");
  if (springback_deg.size() != nominal.bend_angles_deg.size())
    return fail("produced_profile: " + std::to_string(springback_deg.size()) +
                " springback values for " + std::to_string(nominal.bend_angles_deg.size()) +
                " bends");
  ProfileSpec produced = nominal;
  for (std::size_t i = 0; i < springback_deg.size(); ++i) {
    const double a = nominal.bend_angles_deg[i];
    const double magnitude = std::abs(a) - springback_deg[i];
    if (!(magnitude > 0.0 && magnitude < 180.0))
      return fail("produced_profile: bend " + std::to_string(i) + ": springback " +
                  std::to_string(springback_deg[i]) + " deg leaves angle " +
                  std::to_string(magnitude) + " outside (0, 180)");
    produced.bend_angles_deg[i] = a > 0.0 ? magnitude : -magnitude;
  }
  if (!is_valid(produced)) return fail("produced_profile: the produced profile is invalid");
  return produced;
}

Expected<PointCloud> simulate_scan(const ProfileSpec& nominal,
                                   const std::vector<double>& springback_deg,
                                   const ScanSimulationSettings& settings) {
  if (const std::string bad = check_settings(settings); !bad.empty())
    return fail("simulate_scan: " + bad);
  auto produced = produced_profile(nominal, springback_deg);
  if (!produced) return produced.error();
  const auto path = profile_path(*produced);
  std::vector<double> ends;  // cumulative arc length at the end of each element
  for (const auto& e : path) ends.push_back((ends.empty() ? 0.0 : ends.back()) + e.length_mm());
  const double length = ends.back();
  const double width = produced->width_mm;

  std::mt19937_64 rng(settings.seed);
  const auto patches = random_patches(length, width, settings, rng);
  std::uniform_real_distribution<double> us(0.0, length), uy(0.0, width), unit(0.0, 1.0);
  std::uniform_real_distribution<double> outlier(-settings.outlier_max_mm, settings.outlier_max_mm);
  // normal_distribution needs sigma > 0; sigma 0 means a noise-free scan.
  std::normal_distribution<double> noise(0.0, std::max(settings.noise_sigma_mm, 1e-300));
  const bool noisy = settings.noise_sigma_mm > 0.0;

  PointCloud cloud;
  const auto count = static_cast<std::size_t>(settings.point_count);
  cloud.points.reserve(count);
  if (settings.with_normals) cloud.normals.reserve(count);
  while (cloud.points.size() < count) {
    const double s = us(rng), y = uy(rng);
    const bool in_hole = std::any_of(patches.begin(), patches.end(),
                                     [s, y](const Patch& p) { return p.contains(s, y); });
    if (in_hole) continue;
    const auto element = static_cast<std::size_t>(
        std::min<std::ptrdiff_t>(std::upper_bound(ends.begin(), ends.end(), s) - ends.begin(),
                                 static_cast<std::ptrdiff_t>(path.size()) - 1));
    const double t = s - (element == 0 ? 0.0 : ends[element - 1]);
    const PathPoint p = point_at(path[element], std::clamp(t, 0.0, path[element].length_mm()));
    const Vec3 normal = to_3d_direction(p.normal);
    const bool is_outlier = unit(rng) < settings.outlier_fraction;
    const double offset = is_outlier ? outlier(rng) : (noisy ? noise(rng) : 0.0);
    cloud.points.push_back(settings.T_scan_part * (profile_to_3d(p.position, y) + offset * normal));
    if (settings.with_normals) cloud.normals.push_back(settings.T_scan_part.linear() * normal);
  }
  return cloud;
}

}  // namespace springscan::parts
