#pragma once
// Internal to the ICP engine (icp.cpp): the per-pair terms (small_gicp's factors), their
// parallel reduction with per-block partial sums, which pairs are kept, and the one solve.

#include <Eigen/Core>
#include <cstddef>
#include <vector>

#include "analysis/core/small_solvers.hpp"
#include "analysis/registration/icp.hpp"

namespace springscan::analysis::icp_terms {

using analysis::Mat6;
using analysis::Vec6;

/// Where an update turns: about the moved source centroid (conditioning for parts far from the
/// origin), with the rotation scaled by the source's rms radius so that all six unknowns are
/// lengths and the degenerate-direction ratio compares like with like.
struct StepFrame {
  Vec3 center = Vec3::Zero();
  double scale_mm = 1.0;
};

/// Which pairs count in one evaluation.
struct Keep {
  double max_squared_distance_mm2;  ///< trimming, by the distance found by the search
  double max_abs_residual_mm;       ///< robust-sigma threshold on the metric's residual
};

/// Sums over the kept pairs of one block. Both metrics' sums live here; each term fills its own.
struct Partial {
  Mat6 A = Mat6::Zero();  ///< point-to-plane normal equations (Chen-Medioni, linearised)
  Vec6 b = Vec6::Zero();
  Mat3 H = Mat3::Zero();  ///< point-to-point weighted cross-covariance sum (Besl-McKay)
  Vec3 sum_s = Vec3::Zero();
  Vec3 sum_q = Vec3::Zero();
  double sum_w = 0.0;
  double sum_e = 0.0;  ///< unweighted squared residuals: E of paper eq. (1)
  std::size_t count = 0;
  void add(const Partial& o);
};

/// The kept pairs' thresholds at T: the trimming quantile of the search distances and
/// inlier_sigma_factor robust sigmas of |residual| (clamped to [min_inlier_threshold_mm,
/// max_correspondence_distance_mm]). `residuals` and `scratch` are the run's buffers.
Keep keep_thresholds(const std::vector<Vec3>& source, const Transform& T,
                     const std::vector<IcpPair>& pairs, const IcpSettings& s,
                     std::vector<double>& residuals, std::vector<double>& scratch);

/// The sums of every kept pair at T, per block, combined in block order (thread-count
/// independent).
Partial reduce(const std::vector<Vec3>& source, const Transform& T,
               const std::vector<IcpPair>& pairs, const StepFrame& frame, const Keep& keep,
               const IcpSettings& s);

/// One update from the sums, as a world-frame motion applied after T.
struct Step {
  Transform motion = Transform::Identity();
  double angle_rad = 0.0;       ///< how far it turns
  double translation_mm = 0.0;  ///< how far it moves the centre
  int determined_directions = 6;
};

/// Point-to-point: closed-form weighted Kabsch. Point-to-plane: the 6x6 normal equations solved
/// in the span of the eigenvectors whose eigenvalue exceeds degenerate_eigenvalue_ratio x the
/// largest; the other directions get no motion.
Step solve(const Partial& sums, const StepFrame& frame, const IcpSettings& s);

}  // namespace springscan::analysis::icp_terms
