#pragma once
// Covariances of the least-squares surfaces a flange is measured by (docs/uncertainty.md), from
// its own inlier points in its frame (s across, t along the bend line, h along the normal; see
// analysis/springback/flange_shape.hpp): Cov(beta) = sigma^2 (X^T X)^-1 with sigma^2 the
// residual variance over n - p degrees of freedom (GUM Type A). The fits repeat the ones the
// springback stage made on the same points, only to get their normal matrices and residuals.
//
// Thread safety: pure functions.

#include <Eigen/Core>
#include <cstdint>
#include <span>

#include "analysis/core/point_cloud.hpp"

namespace springscan::analysis {

/// h = c + b_s s + b_t t over the chosen points.
struct PlaneCovariance {
  bool ok = false;  ///< at least 6 points that fix both slopes
  std::size_t points = 0;
  double sigma_mm = 0.0;  ///< rms residual over n - 3 degrees of freedom
  Eigen::Matrix3d inverse_normal = Eigen::Matrix3d::Zero();  ///< (X^T X)^-1, order (c, b_s, b_t)
  Eigen::Matrix2d scatter = Eigen::Matrix2d::Zero();         ///< in-plane (s, t) scatter / n, mm^2
  /// The slope's variance in the in-plane direction w = (w_s, w_t) (unit), for noise sigma:
  /// the tilt variance (rad^2) across a bend whose across direction is w.
  double slope_variance(const Eigen::Vector2d& w, double noise_mm) const {
    return noise_mm * noise_mm * w.dot(inverse_normal.bottomRightCorner<2, 2>() * w);
  }
  /// The rms distance of the points from their centroid along w (mm).
  double spread_mm(const Eigen::Vector2d& w) const { return std::sqrt(w.dot(scatter * w)); }
};

/// The plane of the inliers of `local` (flags in `inlier`, same order; all when empty).
PlaneCovariance plane_covariance(std::span<const Vec3> local, std::span<const std::uint8_t> inlier);

/// The curl model A (s^2 + h^2) + B s + G t s + C + E t = h over the inliers.
struct CurlCovariance {
  bool ok = false;
  std::size_t points = 0;
  double sigma_mm = 0.0;  ///< rms residual over n - 5 degrees of freedom
  Eigen::Matrix<double, 5, 5> inverse_normal =
      Eigen::Matrix<double, 5, 5>::Zero();  ///< order (A, B, G, C, E)
  /// Variance of the slope dh/ds (rad^2) at (s, t), and of dh/dt, for noise sigma.
  double slope_s_variance(double s, double t, double noise_mm) const;
  double slope_t_variance(double s, double noise_mm) const;
  double a_variance(double noise_mm) const { return noise_mm * noise_mm * inverse_normal(0, 0); }
};

CurlCovariance curl_covariance(std::span<const Vec3> local, std::span<const std::uint8_t> inlier);

/// Variance of the radius of a circular arc fitted to `points` points spread evenly over
/// `sweep_rad` with radial noise sigma (centre and radius free): sigma^2 [(J^T J)^-1]_RR.
double arc_radius_variance(double sweep_rad, std::size_t points, double sigma_mm);

}  // namespace springscan::analysis
