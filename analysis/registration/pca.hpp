#pragma once
// PCA alignment (paper §3): move the source so that its centroid and principal axes coincide
// with the target's. The axes' signs and, for near-equal eigenvalues, their order are not
// defined by the eigen-decomposition, and a partial scan may even order its axes differently
// from the model. So every proper rotation mapping source axes onto target axes (the 24
// signed permutations with det = +1), plus finer turns about the sheet normal, is tried. A
// partial scan's centroid is not the model's either: where the rotated scan is clearly shorter
// than the model along a model axis, it is also tried pushed against either end of the model's
// box. Every start is refined by a short trimmed ICP on a sample, the best go on for longer, the
// best distinct poses among them are refined further and the best of those by a robust (trimmed)
// error is kept; the global fit then compares the finalists on the full model
// (analysis/registration/orientation.hpp). Deterministic: ties go to the lower index.

#include <cstddef>
#include <vector>

#include "analysis/core/expected.hpp"
#include "analysis/core/kdtree.hpp"
#include "analysis/core/point_cloud.hpp"
#include "analysis/registration/icp.hpp"

namespace springscan::analysis {

struct PrincipalFrame {
  Vec3 centroid = Vec3::Zero();
  Mat3 axes = Mat3::Identity();     ///< columns: unit principal axes, largest variance first
  Vec3 eigenvalues = Vec3::Zero();  ///< variances along the axes, mm^2, descending
};

/// Centroid and principal axes (Eigen's SelfAdjointEigenSolver on the covariance).
/// Errors: fewer than 3 points, non-finite coordinates, all points on one line or one point.
Expected<PrincipalFrame> principal_frame(const std::vector<Vec3>& points);

struct PcaAlignSettings {
  std::size_t screen_sample_points = 250;  ///< source points (evenly strided) of the first
                                           ///< round, which every start goes through
  int screen_iterations = 4;               ///< ICP updates per start in the first round
  std::size_t sample_points = 500;         ///< source points (evenly strided) of the later rounds
  int refine_iterations = 8;               ///< ICP updates per survivor
  double refine_trimmed_fraction = 0.2;    ///< share of worst pairs left out while refining
  double score_trimmed_fraction = 0.2;     ///< share of worst distances left out of the score
  int in_plane_steps = 3;                  ///< quarter turn subdivisions about the sheet normal
  double partial_slack_fraction = 0.15;    ///< along a model axis where the rotated scan is
                                           ///< shorter than the model by more than this share of
                                           ///< the model's extent (a partial scan), the scan is
                                           ///< also tried pushed against either end
  std::size_t survivors = 16;              ///< best starts of the first round refined further
  std::size_t finalists = 4;               ///< best candidates refined further, then rescored
  int finalist_iterations = 30;            ///< ICP updates per finalist (partial scans start far)
  double distinct_pose_deg = 5.0;          ///< candidates that ended farther apart than this are
                                           ///< different poses (for the ambiguity); nearer ones
                                           ///< converged to the same pose
  double distinct_pose_mm = 10.0;          ///< ... or whose translations differ by more than this
  int threads = 0;                         ///< candidates refined in parallel, 0 = all cores
};

struct PcaAlignResult {
  Transform T_target_source = Transform::Identity();  ///< best candidate after its short ICP
  Transform T_pca = Transform::Identity();            ///< that candidate's pure PCA alignment
  std::size_t best_candidate = 0;                     ///< index into candidate_scores
  std::vector<double> candidate_scores;  ///< trimmed mean squared distance, mm^2, of every
                                         ///< start (rotation x translation) after the last
                                         ///< round it took part in (comparable within a round)
  double ambiguity = 0.0;  ///< best score / second-best score: near 1 = the part looks symmetric
  std::vector<Transform> finalist_poses;  ///< the distinct finalists after their ICP, best first
};

/// The 24 proper rotations (det = +1) that map the source frame's axes onto the target frame's
/// axes up to order and sign, in a fixed order; then, when `in_plane_steps` > 1, the 8 of them
/// that keep the least-variance axis (a sheet's normal) turned further about that target axis
/// by j/in_plane_steps of a quarter turn (j = 1 .. steps-1): a partial scan's in-plane axes
/// need not match the model's at all.
std::vector<Mat3> pca_rotation_candidates(const PrincipalFrame& source,
                                          const PrincipalFrame& target, int in_plane_steps = 1);

/// Aligns `source` to `target`. Point-to-plane refinement when `target_normals` has one normal
/// per target point, point-to-point otherwise. With `source_normals` (one per source point; a
/// one-sided scan of a solid) every pair and score follows the facing rule
/// (analysis/registration/facing.hpp). Errors: as principal_frame, for either cloud; normals
/// of the wrong count.
Expected<PcaAlignResult> pca_align(const std::vector<Vec3>& source, const KdTree& target,
                                   const std::vector<Vec3>& target_normals,
                                   const PcaAlignSettings& settings = {},
                                   const std::vector<Vec3>& source_normals = {});

}  // namespace springscan::analysis
