#include "analysis/registration/icp.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <limits>

#include "analysis/core/parallel.hpp"

namespace springscan::analysis {
namespace {

using Vec6 = Eigen::Matrix<double, 6, 1>;
using Mat6 = Eigen::Matrix<double, 6, 6>;
constexpr std::uint32_t kNoPair = std::numeric_limits<std::uint32_t>::max();

// Nearest target point of every transformed source point (kNoPair beyond the distance limit).
struct Pairs {
  std::vector<std::uint32_t> target;
  std::vector<double> d2;       // squared point-to-point distance of the pair, mm^2
  std::vector<double> scratch;  // for the trimming quantile
};

// Sums over the kept pairs of one block. Both metrics' sums are kept so one pass serves both.
struct Partial {
  Mat6 A = Mat6::Zero();  // point-to-plane normal equations (Chen-Medioni, linearised)
  Vec6 b = Vec6::Zero();
  Mat3 H = Mat3::Zero();  // point-to-point weighted cross-covariance sum (Besl-McKay)
  Vec3 sum_s = Vec3::Zero();
  Vec3 sum_q = Vec3::Zero();
  double sum_w = 0.0;
  double sum_e = 0.0;  // unweighted squared residuals: E of paper eq. (1)
  std::size_t count = 0;
  void add(const Partial& o) {
    A += o.A;
    b += o.b;
    H += o.H;
    sum_s += o.sum_s;
    sum_q += o.sum_q;
    sum_w += o.sum_w;
    sum_e += o.sum_e;
    count += o.count;
  }
};

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

void find_pairs(const std::vector<Vec3>& source, const Transform& T, const KdTree& target,
                const IcpSettings& s, Pairs& pairs) {
  const double limit = s.max_correspondence_distance_mm > 0.0
                           ? s.max_correspondence_distance_mm
                           : std::numeric_limits<double>::infinity();
  parallel_blocks(source.size(), s.threads, [&](std::size_t, std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      const auto hit = target.nearest(T * source[i], limit);
      pairs.target[i] = hit ? hit->index : kNoPair;
      pairs.d2[i] = hit ? hit->squared_distance : 0.0;
    }
  });
}

// The largest pair distance^2 kept after trimming the farthest `trimmed_fraction` of pairs.
double trim_threshold(Pairs& pairs, double trimmed_fraction) {
  if (trimmed_fraction <= 0.0) return std::numeric_limits<double>::infinity();
  pairs.scratch.clear();
  for (std::size_t i = 0; i < pairs.d2.size(); ++i)
    if (pairs.target[i] != kNoPair) pairs.scratch.push_back(pairs.d2[i]);
  if (pairs.scratch.empty()) return 0.0;
  const auto m = pairs.scratch.size();
  const auto drop = static_cast<std::size_t>(std::floor(trimmed_fraction * static_cast<double>(m)));
  const auto kth =
      pairs.scratch.begin() + static_cast<std::ptrdiff_t>(m - std::min(drop, m - 1) - 1);
  std::nth_element(pairs.scratch.begin(), kth, pairs.scratch.end());
  return *kth;
}

// One pair's contribution. `c` is the rotation centre: working relative to the source centroid
// keeps the 6x6 system well conditioned for parts far from the origin.
void add_pair(const Vec3& x, const Vec3& q, const Vec3* n, const Vec3& c, const IcpSettings& s,
              Partial& p) {
  const Vec3 xs = x - c, qs = q - c;
  if (s.method == IcpMethod::kPointToPlane) {
    const double r = n->dot(x - q);
    const double w = kernel_weight(std::abs(r), s);
    Vec6 J;
    J << xs.cross(*n), *n;
    p.A.noalias() += w * J * J.transpose();
    p.b.noalias() += w * r * J;
    p.sum_e += r * r;
  } else {
    const double e2 = (x - q).squaredNorm();
    const double w = kernel_weight(std::sqrt(e2), s);
    p.H.noalias() += w * xs * qs.transpose();
    p.sum_s += w * xs;
    p.sum_q += w * qs;
    p.sum_w += w;
    p.sum_e += e2;
  }
  ++p.count;
}

Partial accumulate(const std::vector<Vec3>& source, const Transform& T, const Vec3& c,
                   const KdTree& target, const std::vector<Vec3>& normals, const Pairs& pairs,
                   double threshold, const IcpSettings& s) {
  std::vector<Partial> partials(block_count(source.size()));
  parallel_blocks(source.size(), s.threads,
                  [&](std::size_t blk, std::size_t begin, std::size_t end) {
                    Partial& p = partials[blk];
                    for (std::size_t i = begin; i < end; ++i) {
                      const std::uint32_t j = pairs.target[i];
                      if (j == kNoPair || pairs.d2[i] > threshold) continue;
                      const Vec3* n = s.method == IcpMethod::kPointToPlane ? &normals[j] : nullptr;
                      add_pair(T * source[i], target.points()[j], n, c, s, p);
                    }
                  });
  Partial total;
  for (const auto& p : partials) total.add(p);  // fixed order: thread-count independent
  return total;
}

// A rotation R about centre c followed by translation t, as a world-frame transform.
Transform about_center(const Mat3& R, const Vec3& t, const Vec3& c) {
  Transform step = Transform::Identity();
  step.linear() = R;
  step.translation() = c + t - R * c;
  return step;
}

// Closed-form weighted least squares (Kabsch/Umeyama via SVD, Besl-McKay step).
Transform solve_point_to_point(const Partial& p, const Vec3& c) {
  const Vec3 ms = p.sum_s / p.sum_w, mq = p.sum_q / p.sum_w;
  const Mat3 H = p.H / p.sum_w - ms * mq.transpose();
  Eigen::JacobiSVD<Mat3> svd(H, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Mat3 D = Mat3::Identity();
  if ((svd.matrixV() * svd.matrixU().transpose()).determinant() < 0.0) D(2, 2) = -1.0;
  const Mat3 R = svd.matrixV() * D * svd.matrixU().transpose();
  return about_center(R, mq - R * ms, c);
}

// Linearised Chen-Medioni step: minimise sum w (n.(x + w x xs + t - q))^2 over (omega, t).
// Directions the surface does not constrain (a plane slides in itself) get a zero update.
Transform solve_point_to_plane(const Partial& p, const Vec3& c, bool& degenerate) {
  Eigen::SelfAdjointEigenSolver<Mat6> eig(p.A);
  const Vec6 lambda = eig.eigenvalues();
  const double cutoff = 1e-10 * std::max(lambda.maxCoeff(), 0.0);
  Vec6 x = Vec6::Zero();
  const Vec6 rhs = eig.eigenvectors().transpose() * (-p.b);
  for (int k = 0; k < 6; ++k) {
    if (lambda(k) > cutoff)
      x += eig.eigenvectors().col(k) * (rhs(k) / lambda(k));
    else
      degenerate = true;
  }
  const Vec3 omega = x.head<3>();
  const double angle = omega.norm();
  const Mat3 R = angle > 0.0 ? Mat3(Eigen::AngleAxisd(angle, omega / angle)) : Mat3::Identity();
  return about_center(R, x.tail<3>(), c);
}

std::optional<Error> check_inputs(const std::vector<Vec3>& source, const KdTree& target,
                                  const std::vector<Vec3>& normals, const IcpSettings& s) {
  if (auto error = validate(s)) return error;
  if (source.empty()) return fail("icp: the source cloud is empty");
  if (target.empty()) return fail("icp: the target cloud is empty");
  if (!all_finite(source) || !all_finite(target.points()))
    return fail("icp: input has non-finite (NaN/inf) coordinates");
  if (s.method == IcpMethod::kPointToPlane && normals.size() != target.size())
    return fail("icp: point-to-plane needs one target normal per point, got " +
                std::to_string(normals.size()) + " for " + std::to_string(target.size()));
  return std::nullopt;
}

}  // namespace

double IcpResult::rms_mm() const {
  return error_history.empty() ? 0.0 : std::sqrt(std::max(error_history.back(), 0.0));
}

std::optional<Error> validate(const IcpSettings& s) {
  auto bad = [](const char* field, double value, const char* why) {
    return fail(std::string("icp: ") + field + " = " + std::to_string(value) + ": " + why);
  };
  if (s.max_iterations < 0) return bad("max_iterations", s.max_iterations, "must be >= 0");
  if (!(s.max_correspondence_distance_mm >= 0.0))
    return bad("max_correspondence_distance_mm", s.max_correspondence_distance_mm, "must be >= 0");
  if (!(s.trimmed_fraction >= 0.0 && s.trimmed_fraction < 1.0))
    return bad("trimmed_fraction", s.trimmed_fraction, "must be in [0, 1)");
  if (!(s.kernel_scale_mm > 0.0)) return bad("kernel_scale_mm", s.kernel_scale_mm, "must be > 0");
  if (!(s.min_error_mm >= 0.0)) return bad("min_error_mm", s.min_error_mm, "must be >= 0");
  if (!(s.error_ratio_stop >= 0.0 && s.error_ratio_stop <= 1.0))
    return bad("error_ratio_stop", s.error_ratio_stop, "must be in [0, 1]");
  return std::nullopt;
}

Expected<IcpResult> icp(const std::vector<Vec3>& source, const KdTree& target,
                        const std::vector<Vec3>& target_normals, const Transform& initial,
                        const IcpSettings& s) {
  if (auto error = check_inputs(source, target, target_normals, s)) return *error;
  IcpResult result;
  result.T_target_source = initial;
  Vec3 centroid = Vec3::Zero();
  for (const auto& p : source) centroid += p;
  centroid /= static_cast<double>(source.size());
  const std::size_t needed = s.method == IcpMethod::kPointToPlane ? 6 : 3;
  Pairs pairs{std::vector<std::uint32_t>(source.size()), std::vector<double>(source.size()), {}};
  bool small_step = false;
  for (int i = 0;; ++i) {
    Transform& T = result.T_target_source;
    find_pairs(source, T, target, s, pairs);
    const double threshold = trim_threshold(pairs, s.trimmed_fraction);
    const Vec3 c = T * centroid;
    const Partial sums = accumulate(source, T, c, target, target_normals, pairs, threshold, s);
    result.inliers = sums.count;
    if (sums.count < needed) {
      result.stop_reason = "too few pairs (" + std::to_string(sums.count) + ")";
      break;
    }
    const double E = sums.sum_e / static_cast<double>(sums.count);
    result.error_history.push_back(E);
    const double previous = i > 0 ? result.error_history[result.error_history.size() - 2] : 0.0;
    result.converged = true;
    if (small_step) {
      result.stop_reason = "increment";
      break;
    }
    if (std::sqrt(E) <= s.min_error_mm) {
      result.stop_reason = "error";
      break;
    }
    // Paper Figure 6b: E(i)/E(i-1) near 1 means no further progress. A rise counts too: with
    // trimming, the kept set can flip between two near-equal states at the noise floor.
    if (i > 1 && previous > 0.0 && E / previous > s.error_ratio_stop) {
      result.stop_reason = "ratio";
      break;
    }
    result.converged = false;
    if (i >= s.max_iterations) {
      result.stop_reason = "iterations";
      break;
    }
    const Transform step = s.method == IcpMethod::kPointToPlane
                               ? solve_point_to_plane(sums, c, result.degenerate)
                               : solve_point_to_point(sums, c);
    if (!step.matrix().allFinite()) {
      result.stop_reason = "numerical failure";
      break;
    }
    T = step * T;
    ++result.iterations;
    const double angle = Eigen::AngleAxisd(step.linear()).angle();
    small_step = angle < s.rotation_tolerance_rad &&
                 (step.translation() + step.linear() * c - c).norm() < s.translation_tolerance_mm;
  }
  return result;
}

}  // namespace springscan::analysis
