#include "analysis/uncertainty/fit_covariance.hpp"

#include <Eigen/Dense>
#include <cmath>
#include <limits>

namespace springscan::analysis {
namespace {

// (X^T X)^-1 when X^T X is well conditioned, else nothing (the points do not fix the fit).
template <int N>
bool invert(const Eigen::Matrix<double, N, N>& normal, Eigen::Matrix<double, N, N>& inverse) {
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, N, N>> eig(normal);
  const auto& values = eig.eigenvalues();
  if (!(values(0) > 1e-12 * values(N - 1)) || !(values(0) > 0.0)) return false;
  inverse =
      eig.eigenvectors() * values.cwiseInverse().asDiagonal() * eig.eigenvectors().transpose();
  return true;
}

}  // namespace

PlaneCovariance plane_covariance(std::span<const Vec3> local,
                                 std::span<const std::uint8_t> inlier) {
  PlaneCovariance out;
  // Centred on the points' own mean in (s, t), so that the normal matrix is well conditioned.
  Eigen::Vector2d mean = Eigen::Vector2d::Zero();
  Eigen::Matrix2d second = Eigen::Matrix2d::Zero();
  const auto used = [&](std::size_t i) { return inlier.empty() || inlier[i]; };
  for (std::size_t i = 0; i < local.size(); ++i) {
    if (!used(i)) continue;
    const Eigen::Vector2d st(local[i].x(), local[i].y());
    mean += st;
    second += st * st.transpose();
    ++out.points;
  }
  if (out.points < 6) return out;
  const double n = static_cast<double>(out.points);
  mean /= n;
  out.scatter = second / n - mean * mean.transpose();
  Eigen::Matrix3d normal = Eigen::Matrix3d::Zero();
  normal(0, 0) = n;
  normal.bottomRightCorner<2, 2>() = n * out.scatter;
  if (!invert<3>(normal, out.inverse_normal)) return out;
  // The fit (centred coordinates), then its residuals.
  Eigen::Vector3d rhs = Eigen::Vector3d::Zero();
  const auto height = [](const Vec3& q) { return q.z(); };
  for (std::size_t i = 0; i < local.size(); ++i) {
    if (!used(i)) continue;
    const Eigen::Vector3d x(1.0, local[i].x() - mean.x(), local[i].y() - mean.y());
    rhs += x * height(local[i]);
  }
  const Eigen::Vector3d beta = out.inverse_normal * rhs;
  double rss = 0.0;
  for (std::size_t i = 0; i < local.size(); ++i) {
    if (!used(i)) continue;
    const Eigen::Vector3d x(1.0, local[i].x() - mean.x(), local[i].y() - mean.y());
    const double r = height(local[i]) - x.dot(beta);
    rss += r * r;
  }
  out.sigma_mm = std::sqrt(rss / (n - 3.0));
  out.ok = true;
  return out;
}

double CurlCovariance::slope_s_variance(double s, double t, double noise_mm) const {
  Eigen::Matrix<double, 5, 1> g;
  g << 2.0 * s, 1.0, t, 0.0, 0.0;  // d/d(A, B, G, C, E) of 2 A s + B + G t
  return noise_mm * noise_mm * g.dot(inverse_normal * g);
}

double CurlCovariance::slope_t_variance(double s, double noise_mm) const {
  Eigen::Matrix<double, 5, 1> g;
  g << 0.0, 0.0, s, 0.0, 1.0;  // of G s + E
  return noise_mm * noise_mm * g.dot(inverse_normal * g);
}

CurlCovariance curl_covariance(std::span<const Vec3> local, std::span<const std::uint8_t> inlier) {
  using Vec5 = Eigen::Matrix<double, 5, 1>;
  CurlCovariance out;
  Eigen::Matrix<double, 5, 5> normal = Eigen::Matrix<double, 5, 5>::Zero();
  Vec5 rhs = Vec5::Zero();
  const auto row = [](const Vec3& q) {
    Vec5 x;
    x << q.x() * q.x() + q.z() * q.z(), q.x(), q.y() * q.x(), 1.0, q.y();
    return x;
  };
  for (std::size_t i = 0; i < local.size(); ++i) {
    if (!inlier.empty() && !inlier[i]) continue;
    const Vec5 x = row(local[i]);
    normal += x * x.transpose();
    rhs += x * local[i].z();
    ++out.points;
  }
  if (out.points < 10 || !invert<5>(normal, out.inverse_normal)) return out;
  const Vec5 beta = out.inverse_normal * rhs;
  double rss = 0.0;
  for (std::size_t i = 0; i < local.size(); ++i) {
    if (!inlier.empty() && !inlier[i]) continue;
    const double r = local[i].z() - row(local[i]).dot(beta);
    rss += r * r;
  }
  out.sigma_mm = std::sqrt(rss / (static_cast<double>(out.points) - 5.0));
  out.ok = true;
  return out;
}

double arc_radius_variance(double sweep_rad, std::size_t points, double sigma_mm) {
  if (points < 3 || !(sweep_rad > 0.0)) return std::numeric_limits<double>::infinity();
  // Radial residual of a point at polar angle phi: derivatives (-cos, -sin, -1) by the centre
  // (x, y) and the radius; the points evenly over the sweep (a quadrature of 64 nodes).
  constexpr int kNodes = 64;
  Eigen::Matrix3d normal = Eigen::Matrix3d::Zero();
  for (int k = 0; k < kNodes; ++k) {
    const double phi = sweep_rad * ((k + 0.5) / kNodes - 0.5);
    const Eigen::Vector3d j(std::cos(phi), std::sin(phi), 1.0);
    normal += j * j.transpose();
  }
  normal *= static_cast<double>(points) / kNodes;
  Eigen::Matrix3d inverse;
  if (!invert<3>(normal, inverse)) return std::numeric_limits<double>::infinity();
  return sigma_mm * sigma_mm * inverse(2, 2);
}

}  // namespace springscan::analysis
