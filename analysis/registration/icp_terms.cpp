#include "analysis/registration/icp_terms.hpp"

#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <limits>

#include "analysis/core/parallel.hpp"

namespace springscan::analysis::icp_terms {
namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();
// Median |residual| x this = the standard deviation of Gaussian residuals (the MAD estimator).
constexpr double kMadToSigma = 1.4826;

double kernel_weight(double r, const IcpSettings& s) {
  const double k = s.kernel_scale_mm;
  switch (s.kernel) {
    case RobustKernel::kHuber:
      return r <= k ? 1.0 : k / r;
    case RobustKernel::kTukey: {
      if (r >= k) return 0.0;
      const double u = 1.0 - (r / k) * (r / k);
      return u * u;
    }
    case RobustKernel::kNone:
      break;
  }
  return 1.0;
}

// Chen-Medioni: r = n . (x - q), linearised for a small rotation omega about the frame's
// centre and a translation t: r ~ r + (x - c) x n . omega + n . t, omega scaled by the radius.
struct PointToPlane {
  static double residual(const Vec3& x, const IcpPair& p) { return p.normal.dot(x - p.point); }
  static void linearize(const Vec3& x, const IcpPair& p, const StepFrame& f, const Keep& keep,
                        const IcpSettings& s, Partial& out) {
    const double r = residual(x, p);
    if (std::abs(r) > keep.max_abs_residual_mm) return;
    const double w = kernel_weight(std::abs(r), s);
    Vec6 J;
    J << (x - f.center).cross(p.normal) / f.scale_mm, p.normal;
    out.A.noalias() += w * J * J.transpose();
    out.b.noalias() += w * r * J;
    out.sum_e += r * r;
    ++out.count;
  }
};

// Besl-McKay: the weighted cross-covariance of the pairs relative to the frame's centre.
struct PointToPoint {
  static double residual(const Vec3& x, const IcpPair& p) { return (x - p.point).norm(); }
  static void linearize(const Vec3& x, const IcpPair& p, const StepFrame& f, const Keep& keep,
                        const IcpSettings& s, Partial& out) {
    const double e2 = (x - p.point).squaredNorm();
    const double r = std::sqrt(e2);
    if (r > keep.max_abs_residual_mm) return;
    const double w = kernel_weight(r, s);
    const Vec3 xs = x - f.center, qs = p.point - f.center;
    out.H.noalias() += w * xs * qs.transpose();
    out.sum_s += w * xs;
    out.sum_q += w * qs;
    out.sum_w += w;
    out.sum_e += e2;
    ++out.count;
  }
};

template <typename Term>
Partial reduce_terms(const std::vector<Vec3>& source, const Transform& T,
                     const std::vector<IcpPair>& pairs, const StepFrame& frame, const Keep& keep,
                     const IcpSettings& s) {
  std::vector<Partial> partials(block_count(source.size()));
  parallel_blocks(source.size(), s.threads,
                  [&](std::size_t block, std::size_t begin, std::size_t end) {
                    Partial& out = partials[block];
                    for (std::size_t i = begin; i < end; ++i) {
                      const IcpPair& p = pairs[i];
                      if (!p.valid || p.squared_distance_mm2 > keep.max_squared_distance_mm2)
                        continue;
                      Term::linearize(T * source[i], p, frame, keep, s, out);
                    }
                  });
  Partial total;
  for (const auto& p : partials) total.add(p);  // fixed order: thread-count independent
  return total;
}

// The largest search distance^2 kept after trimming the farthest `trimmed_fraction` of pairs.
double trim_threshold(const std::vector<IcpPair>& pairs, double trimmed_fraction,
                      std::vector<double>& scratch) {
  if (trimmed_fraction <= 0.0) return kInfinity;
  scratch.clear();
  for (const IcpPair& p : pairs)
    if (p.valid) scratch.push_back(p.squared_distance_mm2);
  if (scratch.empty()) return 0.0;
  const auto m = scratch.size();
  const auto drop = static_cast<std::size_t>(std::floor(trimmed_fraction * static_cast<double>(m)));
  const auto kth = scratch.begin() + static_cast<std::ptrdiff_t>(m - std::min(drop, m - 1) - 1);
  std::nth_element(scratch.begin(), kth, scratch.end());
  return *kth;
}

// inlier_sigma_factor robust sigmas of the valid pairs' |residual| at T, clamped.
template <typename Term>
double sigma_threshold(const std::vector<Vec3>& source, const Transform& T,
                       const std::vector<IcpPair>& pairs, const IcpSettings& s,
                       std::vector<double>& residuals, std::vector<double>& scratch) {
  if (s.inlier_sigma_factor <= 0.0) return kInfinity;
  parallel_blocks(source.size(), s.threads, [&](std::size_t, std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i)
      if (pairs[i].valid) residuals[i] = std::abs(Term::residual(T * source[i], pairs[i]));
  });
  scratch.clear();
  for (std::size_t i = 0; i < pairs.size(); ++i)
    if (pairs[i].valid) scratch.push_back(residuals[i]);
  if (scratch.empty()) return 0.0;
  const auto mid = scratch.begin() + static_cast<std::ptrdiff_t>(scratch.size() / 2);
  std::nth_element(scratch.begin(), mid, scratch.end());
  const double upper =
      s.max_correspondence_distance_mm > 0.0 ? s.max_correspondence_distance_mm : kInfinity;
  return std::min(std::max(s.inlier_sigma_factor * kMadToSigma * *mid, s.min_inlier_threshold_mm),
                  upper);
}

// A rotation R about centre c followed by translation t, as a world-frame transform.
Transform about_center(const Mat3& R, const Vec3& t, const Vec3& c) {
  Transform step = Transform::Identity();
  step.linear() = R;
  step.translation() = c + t - R * c;
  return step;
}

// Closed-form weighted least squares (Kabsch/Umeyama via SVD, Besl-McKay step).
Step solve_point_to_point(const Partial& p, const StepFrame& f) {
  const Vec3 ms = p.sum_s / p.sum_w, mq = p.sum_q / p.sum_w;
  const Mat3 H = p.H / p.sum_w - ms * mq.transpose();
  Eigen::JacobiSVD<Mat3> svd(H, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Mat3 D = Mat3::Identity();
  if ((svd.matrixV() * svd.matrixU().transpose()).determinant() < 0.0) D(2, 2) = -1.0;
  const Mat3 R = svd.matrixV() * D * svd.matrixU().transpose();
  const Vec3 t = mq - R * ms;
  return {about_center(R, t, f.center), Eigen::AngleAxisd(R).angle(), t.norm(), 6};
}

// Minimises sum w (r + J x)^2 in the span of the significant eigenvectors of A; a plane sliding
// in itself, or a profile along its axis, gets no motion in its free directions.
Step solve_point_to_plane(const Partial& p, const StepFrame& f, double ratio) {
  const SymmetricEigen6 eig = symmetric_eigen(p.A);
  const double largest = std::max(eig.values.maxCoeff(), 0.0);
  Vec6 x = Vec6::Zero();
  int determined = 0;
  for (int k = 0; k < 6; ++k) {
    const double lambda = eig.values(k);
    if (!(lambda > ratio * largest) || !(lambda > 0.0)) continue;
    const Vec6 u = eig.vectors.col(k);
    x -= (u.dot(p.b) / lambda) * u;
    ++determined;
  }
  const Vec3 omega = x.head<3>() / f.scale_mm;
  const double angle = omega.norm();
  const Mat3 R = angle > 0.0 ? Mat3(Eigen::AngleAxisd(angle, omega / angle)) : Mat3::Identity();
  return {about_center(R, x.tail<3>(), f.center), angle, x.tail<3>().norm(), determined};
}

}  // namespace

void Partial::add(const Partial& o) {
  A += o.A;
  b += o.b;
  H += o.H;
  sum_s += o.sum_s;
  sum_q += o.sum_q;
  sum_w += o.sum_w;
  sum_e += o.sum_e;
  count += o.count;
}

Keep keep_thresholds(const std::vector<Vec3>& source, const Transform& T,
                     const std::vector<IcpPair>& pairs, const IcpSettings& s,
                     std::vector<double>& residuals, std::vector<double>& scratch) {
  Keep keep{trim_threshold(pairs, s.trimmed_fraction, scratch), kInfinity};
  keep.max_abs_residual_mm =
      s.method == IcpMethod::kPointToPlane
          ? sigma_threshold<PointToPlane>(source, T, pairs, s, residuals, scratch)
          : sigma_threshold<PointToPoint>(source, T, pairs, s, residuals, scratch);
  return keep;
}

Partial reduce(const std::vector<Vec3>& source, const Transform& T,
               const std::vector<IcpPair>& pairs, const StepFrame& frame, const Keep& keep,
               const IcpSettings& s) {
  return s.method == IcpMethod::kPointToPlane
             ? reduce_terms<PointToPlane>(source, T, pairs, frame, keep, s)
             : reduce_terms<PointToPoint>(source, T, pairs, frame, keep, s);
}

Step solve(const Partial& sums, const StepFrame& frame, const IcpSettings& s) {
  return s.method == IcpMethod::kPointToPlane
             ? solve_point_to_plane(sums, frame, s.degenerate_eigenvalue_ratio)
             : solve_point_to_point(sums, frame);
}

}  // namespace springscan::analysis::icp_terms
