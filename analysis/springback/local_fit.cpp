#include "analysis/springback/local_fit.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>

#include "analysis/core/parallel.hpp"

namespace springscan::analysis {
namespace {

using Vec6 = Eigen::Matrix<double, 6, 1>;
using Mat6 = Eigen::Matrix<double, 6, 6>;
constexpr std::size_t kBlock = 4096;
constexpr double kDegToRad = std::numbers::pi / 180.0;

// One pair: the tangent plane n . x = offset of the model point found for a scan point.
struct Pair {
  Vec3 normal = Vec3::Zero();
  double offset = 0.0;
  bool valid = false;
};

Pair find_pair(const LocalFitTarget& target, const Vec3& p, const LocalFitSettings& st) {
  const PartModel& model = target.model();
  if (st.correspondence == LocalFitCorrespondence::kExactSurface) {
    const SurfaceHit hit = model.distance->closest(p);
    if ((p - hit.foot).norm() > st.max_correspondence_distance_mm) return {};
    return {hit.normal, hit.normal.dot(hit.foot), true};
  }
  const auto nn = target.tree().nearest(p, st.max_correspondence_distance_mm);
  if (!nn) return {};
  const Vec3& n = model.samples.normals[nn->index];
  return {n, n.dot(model.samples.points[nn->index]), true};
}

// Normal equations of the linearised point-to-plane error about `center`, with the rotation
// scaled by `scale` (x = [scale * omega, t]).
struct System {
  Mat6 H = Mat6::Zero();
  Vec6 g = Vec6::Zero();
  double sum_sq = 0.0;
  std::size_t count = 0;
};

// The residual threshold: inlier_sigma_factor robust sigmas (1.4826 * median |r|), clamped.
double inlier_threshold(const std::vector<Pair>& pairs, const std::vector<double>& residuals,
                        const LocalFitSettings& st, std::vector<double>& scratch) {
  scratch.clear();
  for (std::size_t i = 0; i < pairs.size(); ++i)
    if (pairs[i].valid) scratch.push_back(std::abs(residuals[i]));
  if (scratch.empty()) return 0.0;
  const auto mid = scratch.begin() + static_cast<std::ptrdiff_t>(scratch.size() / 2);
  std::nth_element(scratch.begin(), mid, scratch.end());
  const double robust_sigma = 1.4826 * *mid;
  return std::clamp(st.inlier_sigma_factor * robust_sigma, st.min_inlier_threshold_mm,
                    st.max_correspondence_distance_mm);
}

// Everything one fit iterates over; the buffers are allocated once per fit.
struct FitState {
  std::vector<Vec3> source;
  std::vector<Pair> pairs;
  std::vector<double> residuals;
  std::vector<double> scratch;
  Vec3 center0 = Vec3::Zero();
  double scale = 1.0;
};

System accumulate(const FitState& f, const Transform& T, double threshold, int threads) {
  const Vec3 center = T * f.center0;
  std::vector<System> partial(block_count(f.source.size(), kBlock));
  for_each_block(f.source.size(), kBlock, threads,
                 [&](std::size_t b, std::size_t lo, std::size_t hi) {
                   System& s = partial[b];
                   for (std::size_t i = lo; i < hi; ++i) {
                     const Pair& p = f.pairs[i];
                     const double r = f.residuals[i];
                     if (!p.valid || std::abs(r) > threshold) continue;
                     Vec6 J;
                     J << (T * f.source[i] - center).cross(p.normal) / f.scale, p.normal;
                     s.H.noalias() += J * J.transpose();
                     s.g += J * r;
                     s.sum_sq += r * r;
                     ++s.count;
                   }
                 });
  System total;
  for (const System& s : partial) {  // fixed block order: independent of the thread count
    total.H += s.H;
    total.g += s.g;
    total.sum_sq += s.sum_sq;
    total.count += s.count;
  }
  return total;
}

// Solves H x = -g in the span of the significant eigenvectors; the rest stays at zero.
Vec6 solve_determined(const System& sys, double ratio, int& determined) {
  const Eigen::SelfAdjointEigenSolver<Mat6> eig(sys.H);
  const double largest = eig.eigenvalues().maxCoeff();
  Vec6 x = Vec6::Zero();
  determined = 0;
  for (int k = 0; k < 6; ++k) {
    const double lambda = eig.eigenvalues()(k);
    if (!(lambda > ratio * largest) || !(lambda > 0.0)) continue;
    const Vec6 u = eig.eigenvectors().col(k);
    x -= (u.dot(sys.g) / lambda) * u;
    ++determined;
  }
  return x;
}

// One Gauss-Newton step on the current pairs. Returns false when too few pairs are left;
// `small` tells whether the step fell below the convergence settings.
bool gauss_newton_step(FitState& f, Transform& T, const LocalFitSettings& st,
                       LocalFitResult& result, bool record, bool& small) {
  for_each_block(f.source.size(), kBlock, st.threads,
                 [&](std::size_t, std::size_t lo, std::size_t hi) {
                   for (std::size_t i = lo; i < hi; ++i)
                     f.residuals[i] = f.pairs[i].normal.dot(T * f.source[i]) - f.pairs[i].offset;
                 });
  const double threshold = inlier_threshold(f.pairs, f.residuals, st, f.scratch);
  const System sys = accumulate(f, T, threshold, st.threads);
  if (sys.count < 3) return false;
  if (record) result.error_history.push_back(sys.sum_sq / static_cast<double>(sys.count));
  result.inliers = sys.count;
  const Vec6 x =
      solve_determined(sys, st.degenerate_eigenvalue_ratio, result.determined_directions);
  const Vec3 omega = x.head<3>() / f.scale;
  const Vec3 t = x.tail<3>();
  // p' = c + R (p - c) + t: the update turns about the current centroid.
  const Vec3 center = T * f.center0;
  Transform step = Transform::Identity();
  if (omega.norm() > 0.0)
    step.linear() = Eigen::AngleAxisd(omega.norm(), omega.normalized()).toRotationMatrix();
  step.translation() = center + t - step.linear() * center;
  T = step * T;
  small = omega.norm() < st.convergence_rotation_deg * kDegToRad &&
          t.norm() < st.convergence_translation_mm;
  return true;
}

}  // namespace

LocalFitTarget::LocalFitTarget(const PartModel& model)
    : model_(&model), tree_(model.samples.points) {}

Expected<LocalFitResult> local_fit(const LocalFitTarget& target, const PointCloud& scan,
                                   const std::vector<std::uint32_t>& indices,
                                   const LocalFitSettings& st) {
  const PartModel& model = target.model();
  if (indices.size() < static_cast<std::size_t>(std::max(st.min_points, 3)))
    return fail("local_fit: subset has " + std::to_string(indices.size()) +
                " points, fewer than min_points " + std::to_string(st.min_points));
  if (model.samples.empty() || model.samples.normals.size() != model.samples.size())
    return fail("local_fit: the model samples have no normals");
  if (st.correspondence == LocalFitCorrespondence::kExactSurface && !model.distance)
    return fail("local_fit: kExactSurface needs PartModel::distance");
  FitState f;
  f.source.reserve(indices.size());
  for (std::uint32_t i : indices) {
    if (i >= scan.size())
      return fail("local_fit: index " + std::to_string(i) + " outside the scan of " +
                  std::to_string(scan.size()) + " points");
    if (!scan.points[i].allFinite())
      return fail("local_fit: point " + std::to_string(i) + " is not finite");
    f.source.push_back(scan.points[i]);
  }
  // Rotations act about the subset's centroid, scaled by its rms radius (mm vs radians).
  for (const Vec3& p : f.source) f.center0 += p;
  f.center0 /= static_cast<double>(f.source.size());
  double spread = 0.0;
  for (const Vec3& p : f.source) spread += (p - f.center0).squaredNorm();
  f.scale = std::max(std::sqrt(spread / static_cast<double>(f.source.size())), 1e-9);
  f.pairs.resize(f.source.size());
  f.residuals.resize(f.source.size());
  f.scratch.reserve(f.source.size());

  LocalFitResult result;
  result.points = f.source.size();
  Transform& T = result.T_model_subset;
  // ICP: find the pairs, then solve the point-to-plane problem on them to convergence (a few
  // Gauss-Newton steps); stop when fresh pairs no longer move the subset.
  for (int iteration = 0; iteration < st.max_iterations && !result.converged; ++iteration) {
    for_each_block(f.source.size(), kBlock, st.threads,
                   [&](std::size_t, std::size_t lo, std::size_t hi) {
                     for (std::size_t i = lo; i < hi; ++i)
                       f.pairs[i] = find_pair(target, T * f.source[i], st);
                   });
    result.iterations = iteration + 1;
    for (int inner = 0; inner < std::max(st.max_inner_iterations, 1); ++inner) {
      bool small = false;
      if (!gauss_newton_step(f, T, st, result, inner == 0, small))
        return fail("local_fit: fewer than 3 of " + std::to_string(f.source.size()) +
                    " points within " + std::to_string(st.max_correspondence_distance_mm) +
                    " mm of the model");
      if (small) {
        result.converged = inner == 0;
        break;
      }
    }
  }
  result.rms_mm = std::sqrt(result.error_history.back());
  return result;
}

std::vector<std::uint32_t> points_in_box(const PointCloud& scan, const Eigen::AlignedBox3d& box) {
  std::vector<std::uint32_t> out;
  for (std::size_t i = 0; i < scan.size(); ++i)
    if (box.contains(scan.points[i])) out.push_back(static_cast<std::uint32_t>(i));
  return out;
}

std::vector<std::uint32_t> points_on_faces(const LocalFitTarget& target, const PointCloud& scan,
                                           const std::vector<int>& face_ids, double max_distance_mm,
                                           int threads) {
  const auto& samples = target.model().samples;
  std::vector<std::uint8_t> keep(scan.size(), 0);
  if (samples.face_ids.size() == samples.size()) {
    for_each_block(scan.size(), kBlock, threads, [&](std::size_t, std::size_t lo, std::size_t hi) {
      for (std::size_t i = lo; i < hi; ++i) {
        const auto nn = target.tree().nearest(scan.points[i], max_distance_mm);
        keep[i] = nn && std::find(face_ids.begin(), face_ids.end(), samples.face_ids[nn->index]) !=
                            face_ids.end();
      }
    });
  }
  std::vector<std::uint32_t> out;
  for (std::size_t i = 0; i < keep.size(); ++i)
    if (keep[i]) out.push_back(static_cast<std::uint32_t>(i));
  return out;
}

}  // namespace springscan::analysis
