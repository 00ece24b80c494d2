#include "simulators/parts/head_scan.hpp"

#include <cmath>
#include <limits>
#include <numbers>
#include <optional>
#include <random>

namespace springscan::parts {
namespace {

using analysis::Vec3;

struct Triangle {
  Vec3 a, e1, e2, normal;  // normal: unit, either orientation
};

/// Distance along the unit ray (o, d) to the triangle, if it is hit in front of o
/// (Moller-Trumbore, J. Graphics Tools 2(1), 1997).
std::optional<double> hit(const Triangle& t, const Vec3& o, const Vec3& d) {
  const Vec3 p = d.cross(t.e2);
  const double det = t.e1.dot(p);
  if (std::abs(det) < 1e-14) return std::nullopt;
  const Vec3 s = o - t.a;
  const double u = s.dot(p) / det;
  if (u < 0.0 || u > 1.0) return std::nullopt;
  const Vec3 q = s.cross(t.e1);
  const double v = d.dot(q) / det;
  if (v < 0.0 || u + v > 1.0) return std::nullopt;
  const double range = t.e2.dot(q) / det;
  if (range <= 0.0) return std::nullopt;
  return range;
}

std::vector<Triangle> triangles_of(const analysis::TriangleMesh& mesh) {
  std::vector<Triangle> out;
  out.reserve(mesh.triangles.size());
  for (const auto& tri : mesh.triangles) {
    const Vec3& a = mesh.vertices[tri[0]];
    Triangle t{a, mesh.vertices[tri[1]] - a, mesh.vertices[tri[2]] - a, Vec3::Zero()};
    const Vec3 n = t.e1.cross(t.e2);
    if (n.norm() == 0.0) continue;
    t.normal = n.normalized();
    out.push_back(t);
  }
  return out;
}

}  // namespace

analysis::Expected<analysis::PointCloud> head_scan(const analysis::TriangleMesh& mesh,
                                                   const HeadScanSettings& s) {
  if (mesh.triangles.empty()) return analysis::fail("head scan: the mesh is empty");
  if (!(s.point_spacing_mm > 0) || !(s.line_spacing_mm > 0))
    return analysis::fail("head scan: spacings must be > 0");
  if (!(s.outlier_fraction >= 0 && s.outlier_fraction <= 0.5))
    return analysis::fail("head scan: outlier_fraction must lie in [0, 0.5]");
  const auto columns =
      static_cast<std::int64_t>(std::floor((s.x_max_mm - s.x_min_mm) / s.point_spacing_mm)) + 1;
  const auto lines = static_cast<std::int64_t>(
                         std::floor((s.encoder_max_mm - s.encoder_min_mm) / s.line_spacing_mm)) +
                     1;
  if (columns <= 0 || lines <= 0 || columns * lines > 10'000'000)
    return analysis::fail("head scan: the pattern has no rays or more than 10 million");
  const std::vector<Triangle> triangles = triangles_of(mesh);
  const analysis::Mat3 R = s.T_station_head.linear();
  const Vec3 d = R.col(1);  // the head's +z (range) in the station
  const double min_cos = std::cos(s.max_incidence_deg * std::numbers::pi / 180.0);
  std::mt19937_64 rng(s.seed);
  std::normal_distribution<double> noise(0.0, s.noise_sigma_mm);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  analysis::PointCloud cloud;
  for (std::int64_t line = 0; line < lines; ++line) {
    const double e = s.encoder_min_mm + static_cast<double>(line) * s.line_spacing_mm;
    for (std::int64_t column = 0; column < columns; ++column) {
      const double x = s.x_min_mm + static_cast<double>(column) * s.point_spacing_mm;
      const Vec3 o = s.T_station_head * Vec3(x, 0.0, s.motion_scale * e);
      double range = std::numeric_limits<double>::infinity();
      const Triangle* first = nullptr;
      for (const Triangle& t : triangles) {
        const auto r = hit(t, o, d);
        if (r && *r < range) range = *r, first = &t;
      }
      if (first == nullptr || std::abs(first->normal.dot(d)) < min_cos) continue;
      double z = range + (s.noise_sigma_mm > 0 ? noise(rng) : 0.0);
      if (s.outlier_fraction > 0 && unit(rng) < s.outlier_fraction)
        z += (2.0 * unit(rng) - 1.0) * s.outlier_max_mm;
      cloud.points.emplace_back(x, z, e);
    }
  }
  return cloud;
}

namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

// Straight down over the artefact's centre, turned by tilt_deg about tilt_axis through it.
analysis::Transform nominal_head(const Vec3& tilt_axis, double tilt_deg) {
  analysis::Transform down = analysis::Transform::Identity();
  down.linear() << 1, 0, 0,  // head x along station x
      0, 0, 1,               // the encoder travels along station y
      0, -1, 0;              // the range looks down
  down.translation() = Vec3(80, 50, 270);
  const Vec3 centre(80, 50, 30);
  analysis::Transform tilt = analysis::Transform::Identity();
  tilt.linear() = Eigen::AngleAxisd(tilt_deg * kDeg, tilt_axis.normalized()).toRotationMatrix();
  tilt.translation() = centre - tilt.linear() * centre;
  return tilt * down;
}

analysis::Transform mounted_with_error(const analysis::Transform& nominal, const Vec3& axis,
                                       const Vec3& shift) {
  analysis::Transform error = analysis::Transform::Identity();
  error.linear() = Eigen::AngleAxisd(0.5 * kDeg, axis.normalized()).toRotationMatrix();
  error.translation() = 2.0 * shift.normalized();
  return nominal * error;
}

}  // namespace

std::vector<DemoHead> demo_heads() {
  std::vector<DemoHead> heads;
  const auto add = [&](const char* name, const Vec3& tilt_axis, double tilt_deg,
                       const Vec3& error_axis, const Vec3& error_shift) {
    const analysis::Transform nominal = nominal_head(tilt_axis, tilt_deg);
    heads.push_back({name, nominal, mounted_with_error(nominal, error_axis, error_shift)});
  };
  add("a", Vec3::UnitX(), 0.0, Vec3(1, 2, 3), Vec3(1, -1, 0.5));
  add("b", Vec3::UnitX(), 25.0, Vec3(-2, 1, 1), Vec3(0.3, 1, -1));
  add("c", Vec3::UnitY(), -25.0, Vec3(0, 1, -1), Vec3(-1, 0.2, 1));
  return heads;
}

HeadScanSettings demo_head_scan(const analysis::Transform& truth, double motion_scale,
                                std::uint64_t seed) {
  HeadScanSettings s;
  s.T_station_head = truth;
  s.motion_scale = motion_scale;
  s.x_min_mm = -110;
  s.x_max_mm = 110;
  s.encoder_min_mm = -80;
  s.encoder_max_mm = 80;
  s.point_spacing_mm = 1.5;
  s.line_spacing_mm = 1.5;
  s.noise_sigma_mm = 0.02;
  s.outlier_fraction = 0.01;
  s.seed = seed;
  return s;
}

}  // namespace springscan::parts
