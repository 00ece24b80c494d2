#include "analysis/springback/bend_zone.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace springscan::analysis {
namespace {

using Vec5 = Eigen::Matrix<double, 5, 1>;
using Mat5 = Eigen::Matrix<double, 5, 5>;

// Parameters: centre (x, z) at t = 0, its slope per mm of t, radius.
struct Cylinder {
  double x = 0, z = 0, gx = 0, gz = 0, r = 0;
  double distance(const Vec3& q) const {  // signed, q = (x, t, z)
    const double dx = q.x() - x - gx * q.y(), dz = q.z() - z - gz * q.y();
    return std::sqrt(dx * dx + dz * dz) - r;
  }
};

// The algebraic circle x^2 + z^2 + D x + E z + F = 0 of the points projected along the axis.
bool kasa(const std::vector<Vec3>& q, Cylinder& out) {
  Eigen::Matrix3d normal = Eigen::Matrix3d::Zero();
  Eigen::Vector3d rhs = Eigen::Vector3d::Zero();
  for (const Vec3& p : q) {
    const Eigen::Vector3d a(p.x(), p.z(), 1.0);
    normal += a * a.transpose();
    rhs -= a * (p.x() * p.x() + p.z() * p.z());
  }
  const Eigen::Vector3d s = normal.ldlt().solve(rhs);
  out.x = -0.5 * s(0);
  out.z = -0.5 * s(1);
  const double r2 = out.x * out.x + out.z * out.z - s(2);
  if (!(r2 > 0.0) || !s.allFinite()) return false;
  out.r = std::sqrt(r2);
  return true;
}

// One Gauss-Newton step on the points within `threshold`; false when singular.
bool gauss_newton_step(const std::vector<Vec3>& q, double threshold, Cylinder& c) {
  Mat5 normal = Mat5::Zero();
  Vec5 rhs = Vec5::Zero();
  for (const Vec3& p : q) {
    const double dx = p.x() - c.x - c.gx * p.y(), dz = p.z() - c.z - c.gz * p.y();
    const double rho = std::sqrt(dx * dx + dz * dz);
    const double residual = rho - c.r;
    if (!(std::abs(residual) <= threshold) || rho <= 0.0) continue;
    Vec5 j;
    j << -dx / rho, -dz / rho, -p.y() * dx / rho, -p.y() * dz / rho, -1.0;
    normal.noalias() += j * j.transpose();
    rhs -= j * residual;
  }
  const Eigen::LDLT<Mat5> ldlt(normal);
  if (ldlt.info() != Eigen::Success || !(ldlt.rcond() > 1e-14)) return false;
  const Vec5 step = ldlt.solve(rhs);
  if (!step.allFinite()) return false;
  c.x += step(0);
  c.z += step(1);
  c.gx += step(2);
  c.gz += step(3);
  c.r += step(4);
  return true;
}

double robust_sigma(const std::vector<Vec3>& q, const Cylinder& c) {
  std::vector<double> r;
  r.reserve(q.size());
  for (const Vec3& p : q) r.push_back(std::abs(c.distance(p)));
  const auto mid = r.begin() + static_cast<std::ptrdiff_t>(r.size() / 2);
  std::nth_element(r.begin(), mid, r.end());
  return 1.4826 * *mid;
}

}  // namespace

BendZoneFit fit_bend_zone(const PointCloud& cloud, std::span<const std::uint32_t> points,
                          const Vec3& axis_point, const Vec3& axis_direction,
                          const BendZoneSettings& st) {
  BendZoneFit out;
  if (points.size() < static_cast<std::size_t>(std::max(st.min_points, 6))) return out;
  // Frame: e1, e2 across the nominal axis a; q = (x, t, z).
  const Vec3 a = axis_direction.normalized();
  const Vec3 e1 = a.unitOrthogonal(), e2 = a.cross(e1);
  std::vector<Vec3> q;
  q.reserve(points.size());
  for (std::uint32_t i : points) {
    const Vec3 d = cloud.points[i] - axis_point;
    q.emplace_back(d.dot(e1), d.dot(a), d.dot(e2));
  }
  Cylinder c;
  if (!kasa(q, c)) return out;
  double threshold = std::numeric_limits<double>::infinity();
  for (int it = 0; it < st.max_iterations; ++it) {
    const Cylinder before = c;
    if (!gauss_newton_step(q, threshold, c) || !(c.r > 0.0)) return out;
    // Trim once the circle is near, and again once it has settled on the inliers.
    if (it == 2 || it == 5) threshold = std::max(st.outlier_sigmas * robust_sigma(q, c), 1e-9);
    const double moved =
        std::abs(c.x - before.x) + std::abs(c.z - before.z) + std::abs(c.r - before.r);
    if (it > 5 && moved < 1e-7) break;
  }
  double sum2 = 0.0;
  for (const Vec3& p : q) {
    const double d = c.distance(p);
    if (std::abs(d) > threshold) continue;
    sum2 += d * d;
    ++out.inliers;
  }
  out.fitted = out.inliers >= static_cast<std::size_t>(std::max(st.min_points, 6));
  out.radius_mm = c.r;
  out.rms_mm = out.inliers > 0 ? std::sqrt(sum2 / static_cast<double>(out.inliers)) : 0.0;
  out.axis_point = axis_point + c.x * e1 + c.z * e2;
  out.axis_step = a + c.gx * e1 + c.gz * e2;
  out.axis_direction = out.axis_step.normalized();
  return out;
}

}  // namespace springscan::analysis
