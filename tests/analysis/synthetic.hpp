#pragma once
// Synthetic ground truth shared by the analysis tests: an asymmetric free-form surface and
// sheet profiles sampled with exact normals, random rigid motions, noise and outliers.

#include <cmath>
#include <numbers>
#include <random>
#include <vector>

#include "analysis/core/point_cloud.hpp"
#include "simulators/parts/sheet_profile.hpp"

// The analysis tests build their parts with simulators/parts.
namespace springscan::analysis {
using namespace springscan::parts;
}  // namespace springscan::analysis

namespace springscan::analysis::testing {

/// z(x, y) of a free-form patch with bumps at irregular places: no rotational symmetry.
inline double bumpy_height(double x, double y, Eigen::Vector2d* gradient = nullptr) {
  struct Bump {
    double x, y, h, s;
  };
  static const Bump kBumps[] = {
      {30, 20, 8, 200}, {85, 50, 5, 150}, {70, 15, -4, 100}, {15, 55, 3, 80}};
  double z = 0.03 * x + 0.0004 * x * y;
  Eigen::Vector2d g(0.03 + 0.0004 * y, 0.0004 * x);
  for (const auto& b : kBumps) {
    const double dx = x - b.x, dy = y - b.y;
    const double e = b.h * std::exp(-(dx * dx + dy * dy) / b.s);
    z += e;
    g += Eigen::Vector2d(-2 * dx / b.s * e, -2 * dy / b.s * e);
  }
  if (gradient) *gradient = g;
  return z;
}

/// n points of the bumpy patch over [0, 120] x [0, 70] mm, with unit normals (+z side).
inline PointCloud bumpy_surface(std::size_t n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> ux(0.0, 120.0), uy(0.0, 70.0);
  PointCloud cloud;
  for (std::size_t i = 0; i < n; ++i) {
    const double x = ux(rng), y = uy(rng);
    Eigen::Vector2d g;
    const double z = bumpy_height(x, y, &g);
    cloud.points.emplace_back(x, y, z);
    cloud.normals.push_back(Vec3(-g.x(), -g.y(), 1.0).normalized());
  }
  return cloud;
}

/// n points spread by arc length over the reference side of a profile, with exact normals
/// (pointing to the left of the path, i.e. +z on the first flange).
/// Only the stretch of path between the fractions `from` and `to` of its length is sampled when
/// they are given (a scan that sees part of the profile).
inline PointCloud sample_profile(const ProfileSpec& spec, std::size_t n, unsigned seed,
                                 double from = 0.0, double to = 1.0) {
  const auto path = profile_path(spec);
  double total = 0.0;
  for (const auto& e : path) total += e.length_mm();
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> us(from * total, to * total), uy(0.0, spec.width_mm);
  PointCloud cloud;
  for (std::size_t i = 0; i < n; ++i) {
    double s = us(rng);
    std::size_t k = 0;
    while (k + 1 < path.size() && s > path[k].length_mm()) s -= path[k++].length_mm();
    const auto& e = path[k];
    Eigen::Vector2d p, normal;
    if (e.kind == ProfileElement::Kind::kLine) {
      const Eigen::Vector2d d = (e.end - e.start).normalized();
      p = e.start + s * d;
      normal = {-d.y(), d.x()};
    } else {
      const double a = e.start_angle_rad + (e.sweep_rad > 0 ? 1.0 : -1.0) * s / e.radius_mm;
      const Eigen::Vector2d radial(std::cos(a), std::sin(a));
      p = e.center + e.radius_mm * radial;
      normal = e.sweep_rad > 0 ? Eigen::Vector2d(-radial) : radial;
    }
    cloud.points.push_back(profile_to_3d(p, uy(rng)));
    cloud.normals.push_back(profile_to_3d(normal, 0.0));
  }
  return cloud;
}

/// Three draws of `d` as a vector, drawn z first, then y, then x. C++ leaves the order in which
/// a call's arguments are evaluated unspecified: Vec3(d(rng), d(rng), d(rng)) draws z first
/// under g++ and x first under clang, so a test's scenario (its pose, its noise) depended on the
/// compiler. Sequenced here, in g++'s order, the order every scenario was written against.
template <typename Distribution>
Vec3 draw_vec3(Distribution& d, std::mt19937& rng) {
  const double z = d(rng);
  const double y = d(rng);
  const double x = d(rng);
  return {x, y, z};
}

/// n points uniformly distributed in the cube [lo, hi)^3 (fixed seed).
inline std::vector<Vec3> uniform_points(std::size_t n, unsigned seed, double lo = 0.0,
                                        double hi = 100.0) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(lo, hi);
  std::vector<Vec3> points(n);
  for (auto& p : points) p = draw_vec3(u, rng);
  return points;
}

/// A uniformly random rotation (normalised Gaussian quaternion) and a translation in a box.
inline Transform random_motion(std::mt19937& rng, double max_translation_mm) {
  std::normal_distribution<double> g(0.0, 1.0);
  std::uniform_real_distribution<double> u(-max_translation_mm, max_translation_mm);
  const Vec3 xyz = draw_vec3(g, rng);  // z, y, x, then w: see draw_vec3
  const double w = g(rng);
  Eigen::Quaterniond q(w, xyz.x(), xyz.y(), xyz.z());
  q.normalize();
  Transform T = Transform::Identity();
  T.linear() = q.toRotationMatrix();
  T.translation() = draw_vec3(u, rng);
  return T;
}

/// Adds N(0, sigma) to every coordinate.
inline void add_noise(std::vector<Vec3>& points, double sigma_mm, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> g(0.0, sigma_mm);
  for (auto& p : points) p += draw_vec3(g, rng);
}

/// Replaces `fraction` of the points by uniform points in the cloud's box grown by `margin_mm`.
inline void add_outliers(std::vector<Vec3>& points, double fraction, double margin_mm,
                         unsigned seed) {
  Vec3 lo = points[0], hi = points[0];
  for (const auto& p : points) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const auto stride = static_cast<std::size_t>(std::round(1.0 / fraction));
  for (std::size_t i = 0; i < points.size(); i += stride) {
    const Vec3 t = draw_vec3(u, rng);
    points[i] =
        (lo - Vec3::Constant(margin_mm)) + t.cwiseProduct(hi - lo + Vec3::Constant(2 * margin_mm));
  }
}

/// Rotation angle between two rotations, rad.
inline double rotation_error_rad(const Transform& a, const Transform& b) {
  return Eigen::AngleAxisd(a.linear() * b.linear().transpose()).angle();
}

}  // namespace springscan::analysis::testing
