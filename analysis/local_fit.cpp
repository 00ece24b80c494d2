#include "analysis/local_fit.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>

#include "analysis/block_parallel.hpp"

namespace springscan::analysis {
namespace {

using Vec6 = Eigen::Matrix<double, 6, 1>;
using Mat6 = Eigen::Matrix<double, 6, 6>;
constexpr std::size_t kBlock = 4096;
constexpr double kDegToRad = std::numbers::pi / 180.0;

// One pair: the point-to-plane residual r = n . (p - q) and the plane normal n.
struct Pair {
  Vec3 normal = Vec3::Zero();
  double residual = 0.0;
  bool valid = false;
};

Pair find_pair(const LocalFitTarget& target, const Vec3& p, const LocalFitSettings& st) {
  Pair pair;
  const PartModel& model = target.model();
  if (st.correspondence == LocalFitCorrespondence::kExactSurface) {
    const SurfaceHit hit = model.distance->closest(p);
    if ((p - hit.foot).norm() > st.max_correspondence_distance_mm) return pair;
    return {hit.normal, hit.normal.dot(p - hit.foot), true};
  }
  const auto nn = target.tree().nearest(p, st.max_correspondence_distance_mm);
  if (!nn) return pair;
  const Vec3& n = model.samples.normals[nn->index];
  return {n, n.dot(p - model.samples.points[nn->index]), true};
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
double inlier_threshold(const std::vector<Pair>& pairs, const LocalFitSettings& st,
                        std::vector<double>& scratch) {
  scratch.clear();
  for (const Pair& p : pairs)
    if (p.valid) scratch.push_back(std::abs(p.residual));
  if (scratch.empty()) return 0.0;
  const auto mid = scratch.begin() + static_cast<std::ptrdiff_t>(scratch.size() / 2);
  std::nth_element(scratch.begin(), mid, scratch.end());
  const double robust_sigma = 1.4826 * *mid;
  return std::clamp(st.inlier_sigma_factor * robust_sigma, st.min_inlier_threshold_mm,
                    st.max_correspondence_distance_mm);
}

System accumulate(const std::vector<Vec3>& moved, const std::vector<Pair>& pairs,
                  const Vec3& center, double scale, double threshold, int threads) {
  std::vector<System> partial(block_count(moved.size(), kBlock));
  for_each_block(moved.size(), kBlock, threads, [&](std::size_t b, std::size_t lo, std::size_t hi) {
    System& s = partial[b];
    for (std::size_t i = lo; i < hi; ++i) {
      const Pair& p = pairs[i];
      if (!p.valid || std::abs(p.residual) > threshold) continue;
      Vec6 J;
      J << (moved[i] - center).cross(p.normal) / scale, p.normal;
      s.H.noalias() += J * J.transpose();
      s.g += J * p.residual;
      s.sum_sq += p.residual * p.residual;
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
  std::vector<Vec3> source;
  source.reserve(indices.size());
  for (std::uint32_t i : indices) {
    if (i >= scan.size())
      return fail("local_fit: index " + std::to_string(i) + " outside the scan of " +
                  std::to_string(scan.size()) + " points");
    source.push_back(scan.points[i]);
  }
  // Rotations act about the subset's centroid, scaled by its rms radius (metres vs radians).
  Vec3 center0 = Vec3::Zero();
  for (const Vec3& p : source) center0 += p;
  center0 /= static_cast<double>(source.size());
  double spread = 0.0;
  for (const Vec3& p : source) spread += (p - center0).squaredNorm();
  const double scale = std::max(std::sqrt(spread / static_cast<double>(source.size())), 1e-9);

  LocalFitResult result;
  result.points = source.size();
  std::vector<Vec3> moved(source.size());
  std::vector<Pair> pairs(source.size());
  std::vector<double> scratch;
  scratch.reserve(source.size());
  Transform& T = result.T_model_subset;
  for (int iteration = 0; iteration < st.max_iterations; ++iteration) {
    for_each_block(source.size(), kBlock, st.threads,
                   [&](std::size_t, std::size_t lo, std::size_t hi) {
                     for (std::size_t i = lo; i < hi; ++i) {
                       moved[i] = T * source[i];
                       pairs[i] = find_pair(target, moved[i], st);
                     }
                   });
    const double threshold = inlier_threshold(pairs, st, scratch);
    const Vec3 center = T * center0;
    const System sys = accumulate(moved, pairs, center, scale, threshold, st.threads);
    if (sys.count < 3)
      return fail("local_fit: only " + std::to_string(sys.count) + " of " +
                  std::to_string(source.size()) + " points within " +
                  std::to_string(st.max_correspondence_distance_mm) + " mm of the model");
    result.error_history.push_back(sys.sum_sq / static_cast<double>(sys.count));
    result.inliers = sys.count;
    result.iterations = iteration + 1;
    const Vec6 x =
        solve_determined(sys, st.degenerate_eigenvalue_ratio, result.determined_directions);
    const Vec3 omega = x.head<3>() / scale;
    const Vec3 t = x.tail<3>();
    // p' = c + R (p - c) + t: the update turns about the current centroid.
    Transform step = Transform::Identity();
    if (omega.norm() > 0.0)
      step.linear() = Eigen::AngleAxisd(omega.norm(), omega.normalized()).toRotationMatrix();
    step.translation() = center + t - step.linear() * center;
    T = step * T;
    if (omega.norm() < st.convergence_rotation_deg * kDegToRad &&
        t.norm() < st.convergence_translation_mm) {
      result.converged = true;
      break;
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
