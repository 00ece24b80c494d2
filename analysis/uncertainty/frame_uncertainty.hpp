#pragma once
// The expanded uncertainty (k = 2) of the result frame (docs/uncertainty.md): the covariance of
// a point-to-plane fit of the scan's fit points to the model, sigma^2 (J^T J)^-1 with J the rows
// [(p - c) x n, n] of each pair and sigma the pairs' robust residual scale; a direction the
// surface leaves free (an extrusion's length, fixed by the part's ends: registration/boundary)
// takes free_direction_mm; and the station's calibration terms.
//
// Thread safety: pure function (reads the tree).

#include <Eigen/Core>
#include <vector>

#include "analysis/core/kdtree.hpp"
#include "analysis/core/point_cloud.hpp"
#include "analysis/uncertainty/uncertainty.hpp"

namespace springscan::analysis {

struct FrameUncertainty {
  double rotation_deg = 0.0;    ///< expanded: the largest turn (k sigma of the worst axis)
  double translation_mm = 0.0;  ///< expanded: the largest move of a corner of the points' box
  double sigma_mm = 0.0;        ///< the pairs' robust residual scale
  std::size_t pairs = 0;
  /// Standard, for propagating the frame to a value measured in it (frame_statistic_sigma):
  /// the covariance of (rotation about `center` in rad, translation in mm) from the pairs, the
  /// free and weakly fixed directions at free_direction_mm, and what the part's departure from
  /// the CAD does to the fit (its most departed pairs' move, docs/uncertainty.md); the
  /// departure itself (mm) as a move in any direction.
  Eigen::Matrix<double, 6, 6> covariance = Eigen::Matrix<double, 6, 6>::Zero();
  Vec3 center = Vec3::Zero();
  double departure_mm = 0.0;
  double radius_mm = 1.0;
};

/// `points_in_cad`: the fit points in the result frame; `model_tree` over the model samples with
/// `model_normals`. Pairs farther than pair_distance_mm are left out. Fewer than 6 pairs: U is
/// left 0 with pairs telling why.
FrameUncertainty frame_uncertainty(const std::vector<Vec3>& points_in_cad, const KdTree& model_tree,
                                   const std::vector<Vec3>& model_normals,
                                   const UncertaintySettings& settings = {},
                                   double pair_distance_mm = 2.0);

/// The standard uncertainty (mm) that the result frame's uncertainty gives the `quantile` of |d|
/// over `points_in_cad` (1: the largest): its sensitivity to each of the frame's 6 parameters,
/// the mean of sign(d) [(p - c) x n, n] over the points whose |d| ranks next to the quantile (n
/// the nearest model sample's normal), combined with the frame's covariance and its departure.
/// A move that the points near the quantile do not feel (along their surface, or pushing as many
/// out as in) leaves the statistic in place. 0 without points or pairs.
double frame_statistic_sigma(const FrameUncertainty& frame, const std::vector<Vec3>& points_in_cad,
                             const std::vector<double>& signed_distance_mm, double quantile,
                             const KdTree& model_tree, const std::vector<Vec3>& model_normals);

/// The standard uncertainty (mm) of where the result frame puts `point` along the unit
/// `direction`: its covariance's move there, and the departure's move and turn (as above).
double frame_point_sigma(const FrameUncertainty& frame, const Vec3& point, const Vec3& direction);

}  // namespace springscan::analysis
