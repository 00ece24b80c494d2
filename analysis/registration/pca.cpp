#include "analysis/registration/pca.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numeric>

#include "analysis/core/parallel.hpp"
#include "analysis/registration/facing.hpp"

namespace springscan::analysis {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kRadPerDeg = kPi / 180.0;
constexpr double kQuarterTurnRad = kPi / 2.0;
// The robust box of a cloud runs from this quantile to 1 - this along each axis, so that a few
// outliers cannot make a partial scan look as long as the model.
constexpr double kExtentQuantile = 0.01;
// A candidate keeps the sheet normal when it maps the source's least-variance axis within 60
// degrees of the target's; signed permutations give |cos| = 0 or 1, so any value in (0, 1) works.
constexpr double kKeepsNormalCos = 0.5;
// The second variance below this share of the first: the points lie on a line, whose rotation
// about itself no PCA can fix.
constexpr double kCollinearEigenvalueRatio = 1e-10;

// The robust error of a candidate: mean squared nearest distance (to a sample facing the same
// way, on a solid), the worst share left out.
double trimmed_score(const FacingSample& sample, const Transform& T, const KdTree& target,
                     const std::vector<Vec3>& target_normals, double trimmed_fraction) {
  const bool facing = !sample.normals.empty();
  std::vector<double> d2(sample.points.size());
  for (std::size_t i = 0; i < d2.size(); ++i) {
    const Vec3 q = T * sample.points[i];
    d2[i] = facing
                ? facing_squared_distance(target, target_normals, q, T.linear() * sample.normals[i])
                : target.nearest(q)->squared_distance;
  }
  std::sort(d2.begin(), d2.end());
  const auto keep = std::max<std::size_t>(
      1, d2.size() - static_cast<std::size_t>(trimmed_fraction * static_cast<double>(d2.size())));
  double sum = 0.0;
  for (std::size_t i = 0; i < keep && i < d2.size(); ++i) sum += d2[i];
  return sum / static_cast<double>(std::min(keep, d2.size()));
}

double rotation_apart_rad(const Transform& a, const Transform& b) {
  return Eigen::AngleAxisd(a.linear() * b.linear().transpose()).angle();
}

// Refines candidates with a short ICP on a sample and scores them, in parallel.
struct Refiner {
  const KdTree& target;
  const std::vector<Vec3>& normals;
  const PcaAlignSettings& settings;
  IcpSettings icp_settings;

  void run(const FacingSample& sample, const std::vector<std::size_t>& which, int iterations,
           std::vector<Transform>& poses, std::vector<double>& scores) {
    IcpSettings s = icp_settings;
    s.max_iterations = iterations;
    parallel_tasks(which.size(), settings.threads, [&](std::size_t k) {
      const std::size_t i = which[k];
      auto fit = sample.normals.empty()
                     ? icp(sample.points, target, normals, poses[i], s)
                     : icp(sample.points,
                           nearest_facing_pairs(target, normals, sample.normals, 0.0), poses[i], s);
      if (fit) poses[i] = fit->T_target_source;
      scores[i] = trimmed_score(sample, poses[i], target, normals, settings.score_trimmed_fraction);
    });
  }
};

// The lowest score of the last round wins (lowest index on ties): only the finalists have one
// (every score of a round comes from the same sample and the same iterations). Ambiguity
// compares only with finalists that ended in a different pose (more than distinct_pose_deg
// away): starts converging to the same pose agree.
void pick_best(const std::vector<Transform>& poses, const std::vector<std::size_t>& finalists,
               double distinct_pose_deg, PcaAlignResult& result) {
  const auto& scores = result.candidate_scores;
  result.best_candidate = finalists.front();
  for (std::size_t i : finalists)
    if (scores[i] < scores[result.best_candidate] ||
        (scores[i] == scores[result.best_candidate] && i < result.best_candidate))
      result.best_candidate = i;
  double second = std::numeric_limits<double>::infinity();
  for (std::size_t i : finalists)
    if (rotation_apart_rad(poses[i], poses[result.best_candidate]) > distinct_pose_deg * kRadPerDeg)
      second = std::min(second, scores[i]);
  result.ambiguity = second > 0.0 ? scores[result.best_candidate] / second : 1.0;
}

// The best `keep` of `order` (sorted by score) that ended in distinct poses: farther apart than
// distinct_pose_deg in rotation or distinct_pose_mm in translation from every one kept before.
std::vector<std::size_t> distinct_best(const std::vector<std::size_t>& order,
                                       const std::vector<Transform>& poses, std::size_t keep,
                                       const PcaAlignSettings& settings) {
  std::vector<std::size_t> out;
  for (std::size_t i : order) {
    if (out.size() >= keep) break;
    const bool same = std::any_of(out.begin(), out.end(), [&](std::size_t j) {
      return rotation_apart_rad(poses[i], poses[j]) <= settings.distinct_pose_deg * kRadPerDeg &&
             (poses[i].translation() - poses[j].translation()).norm() <= settings.distinct_pose_mm;
    });
    if (!same) out.push_back(i);
  }
  return out;
}

// The 1st and 99th percentile of the points' coordinates along each of the frame's axes
// (a robust box: a few outliers must not make a partial scan look complete).
std::pair<Vec3, Vec3> extent_along(const std::vector<Vec3>& points, const Mat3& axes,
                                   const Mat3& rotation = Mat3::Identity()) {
  const Mat3 project = axes.transpose() * rotation;
  Vec3 lo, hi;
  std::vector<double> along(points.size());
  const auto low_rank =
      static_cast<std::ptrdiff_t>(kExtentQuantile * static_cast<double>(points.size()));
  const auto high_rank = static_cast<std::ptrdiff_t>(points.size()) - 1 - low_rank;
  for (int k = 0; k < 3; ++k) {
    for (std::size_t i = 0; i < points.size(); ++i) along[i] = project.row(k).dot(points[i]);
    std::nth_element(along.begin(), along.begin() + low_rank, along.end());
    lo(k) = along[static_cast<std::size_t>(low_rank)];
    std::nth_element(along.begin(), along.begin() + high_rank, along.end());
    hi(k) = along[static_cast<std::size_t>(high_rank)];
  }
  return {lo, hi};
}

// Where to put the rotated source (start = R * p + t). The centroids aligned (paper §3); and
// where the rotated sample is clearly shorter than the target along a target axis (the scan
// covers part of the part), also pushed against the low and the high end of the target's box.
std::vector<Vec3> translation_hypotheses(const std::vector<Vec3>& sample, const Mat3& R,
                                         const PrincipalFrame& source, const PrincipalFrame& target,
                                         const std::pair<Vec3, Vec3>& target_box,
                                         double slack_fraction) {
  const auto [lo, hi] = extent_along(sample, target.axes, R);
  const Vec3 centred = target.axes.transpose() * (target.centroid - R * source.centroid);
  std::vector<Vec3> offsets{centred};  // in target axes coordinates
  for (int k = 0; k < 3; ++k) {
    const double model_extent = target_box.second(k) - target_box.first(k);
    if (model_extent - (hi(k) - lo(k)) <= slack_fraction * model_extent) continue;
    const std::size_t before = offsets.size();
    for (std::size_t i = 0; i < before; ++i)
      for (double along : {target_box.first(k) - lo(k), target_box.second(k) - hi(k)}) {
        Vec3 o = offsets[i];
        o(k) = along;
        offsets.push_back(o);
      }
  }
  for (auto& o : offsets) o = target.axes * o;
  return offsets;
}

}  // namespace

Expected<PrincipalFrame> principal_frame(const std::vector<Vec3>& points) {
  if (points.size() < 3)
    return fail("pca: needs at least 3 points, got " + std::to_string(points.size()));
  if (!all_finite(points)) return fail("pca: input has non-finite (NaN/inf) coordinates");
  PrincipalFrame frame;
  for (const auto& p : points) frame.centroid += p;
  frame.centroid /= static_cast<double>(points.size());
  Mat3 cov = Mat3::Zero();
  for (const auto& p : points) {
    const Vec3 d = p - frame.centroid;
    cov.noalias() += d * d.transpose();
  }
  cov /= static_cast<double>(points.size());
  Eigen::SelfAdjointEigenSolver<Mat3> solver(cov);
  // Eigen sorts ascending; the paper's principal components come largest first.
  frame.eigenvalues = solver.eigenvalues().reverse().cwiseMax(0.0);
  frame.axes = solver.eigenvectors().rowwise().reverse();
  if (frame.axes.determinant() < 0.0) frame.axes.col(2) = -frame.axes.col(2);
  if (!(frame.eigenvalues(0) > 0.0))
    return fail("pca: all " + std::to_string(points.size()) + " points coincide");
  if (frame.eigenvalues(1) <= kCollinearEigenvalueRatio * frame.eigenvalues(0))
    return fail("pca: all points lie on one line; a rotation about it is undetermined");
  return frame;
}

std::vector<Mat3> pca_rotation_candidates(const PrincipalFrame& source,
                                          const PrincipalFrame& target, int in_plane_steps) {
  std::array<int, 3> order{0, 1, 2};
  std::vector<Mat3> candidates;
  do {
    for (int signs = 0; signs < 8; ++signs) {
      Mat3 P = Mat3::Zero();  // signed permutation: source axis order[k] -> target axis k
      for (int k = 0; k < 3; ++k)
        P(k, order[static_cast<std::size_t>(k)]) = (signs >> k) & 1 ? -1.0 : 1.0;
      const Mat3 R = target.axes * P * source.axes.transpose();
      if (R.determinant() > 0.0) candidates.push_back(R);
    }
  } while (std::next_permutation(order.begin(), order.end()));
  const std::size_t proper = candidates.size();
  const Vec3 normal = target.axes.col(2);
  for (int j = 1; j < in_plane_steps; ++j) {
    const Mat3 turn = Eigen::AngleAxisd(kQuarterTurnRad * j / in_plane_steps, normal).matrix();
    for (std::size_t i = 0; i < proper; ++i)
      if (std::abs(normal.dot(candidates[i] * source.axes.col(2))) > kKeepsNormalCos)
        candidates.push_back(turn * candidates[i]);
  }
  return candidates;
}

Expected<PcaAlignResult> pca_align(const std::vector<Vec3>& source, const KdTree& target,
                                   const std::vector<Vec3>& target_normals,
                                   const PcaAlignSettings& settings,
                                   const std::vector<Vec3>& source_normals) {
  if (!source_normals.empty() &&
      (source_normals.size() != source.size() || target_normals.size() != target.size()))
    return fail(ErrorCode::kInvalidInput,
                "pca: the facing rule needs one normal per source and per target point");
  auto source_frame = principal_frame(source);
  if (!source_frame) return source_frame.error().prepend("scan ");
  auto target_frame = principal_frame(target.points());
  if (!target_frame) return target_frame.error().prepend("model ");
  const auto rotations =
      pca_rotation_candidates(*source_frame, *target_frame, settings.in_plane_steps);
  const FacingSample sample = facing_sample(source, source_normals, settings.sample_points);
  const FacingSample screen_sample =
      facing_sample(source, source_normals, settings.screen_sample_points);
  Refiner refiner{target, target_normals, settings, {}};
  refiner.icp_settings.method =
      target_normals.size() == target.size() ? IcpMethod::kPointToPlane : IcpMethod::kPointToPoint;
  refiner.icp_settings.trimmed_fraction = settings.refine_trimmed_fraction;
  refiner.icp_settings.kernel = RobustKernel::kNone;
  refiner.icp_settings.error_ratio_stop = 1.0;  // a short fixed budget: only a rise ends it early
  refiner.icp_settings.threads = 1;             // parallel over candidates instead
  const auto target_box = extent_along(target.points(), target_frame->axes);
  std::vector<Transform> starts;
  for (const Mat3& R : rotations)
    for (const Vec3& t : translation_hypotheses(sample.points, R, *source_frame, *target_frame,
                                                target_box, settings.partial_slack_fraction)) {
      Transform start = Transform::Identity();
      start.linear() = R;
      start.translation() = t;
      starts.push_back(start);
    }
  PcaAlignResult result;
  std::vector<Transform> refined = starts;
  result.candidate_scores.assign(starts.size(), std::numeric_limits<double>::infinity());
  std::vector<std::size_t> order(starts.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  // Every start gets a very short ICP on a small sample (the screen); the best go on from where
  // they stopped, twice, on a larger sample (a partial scan, whose centroid is off the model's,
  // needs more than a few iterations to settle). Scores are compared within a round only.
  refiner.run(screen_sample, order, settings.screen_iterations, refined, result.candidate_scores);
  const auto by_score = [&](std::size_t a, std::size_t b) {
    return result.candidate_scores[a] < result.candidate_scores[b];
  };
  std::stable_sort(order.begin(), order.end(), by_score);
  order.resize(std::min(order.size(), settings.survivors));
  refiner.run(sample, order, settings.refine_iterations, refined, result.candidate_scores);
  std::stable_sort(order.begin(), order.end(), by_score);
  // The finalists are distinct poses: several starts that settled into the same pose must not
  // crowd out the other orientation of a near-symmetric part.
  order = distinct_best(order, refined, settings.finalists, settings);
  refiner.run(sample, order, settings.finalist_iterations, refined, result.candidate_scores);
  std::stable_sort(order.begin(), order.end(), by_score);
  pick_best(refined, order, settings.distinct_pose_deg, result);
  for (std::size_t i : order) result.finalist_poses.push_back(refined[i]);
  result.T_target_source = refined[result.best_candidate];
  result.T_pca = starts[result.best_candidate];
  return result;
}

}  // namespace springscan::analysis
