#pragma once
// The expanded uncertainty (k = 2) of the result frame (docs/uncertainty.md): the covariance of
// a point-to-plane fit of the scan's fit points to the model, sigma^2 (J^T J)^-1 with J the rows
// [(p - c) x n, n] of each pair and sigma the pairs' robust residual scale; a direction the
// surface leaves free (an extrusion's length, fixed by the part's ends: registration/boundary)
// takes free_direction_mm; and the station's calibration terms.
//
// Thread safety: pure function (reads the tree).

#include <vector>

#include "analysis/core/kdtree.hpp"
#include "analysis/core/point_cloud.hpp"
#include "analysis/uncertainty/uncertainty.hpp"

namespace springscan::analysis {

struct FrameUncertainty {
  double rotation_deg = 0.0;    ///< expanded: the largest turn (k sigma of the worst axis)
  double translation_mm = 0.0;  ///< expanded: the largest move of a corner of the points' box
  /// Expanded, as translation_mm without the part's departure from the CAD and without the free
  /// directions (a slide along them leaves the surface in place): how far a repeated scan moves
  /// this scan's best fit, the frame a deviation statistic is defined in.
  double repeat_translation_mm = 0.0;
  double sigma_mm = 0.0;  ///< the pairs' robust residual scale
  std::size_t pairs = 0;
};

/// `points_in_cad`: the fit points in the result frame; `model_tree` over the model samples with
/// `model_normals`. Pairs farther than pair_distance_mm are left out. Fewer than 6 pairs: U is
/// left 0 with pairs telling why.
FrameUncertainty frame_uncertainty(const std::vector<Vec3>& points_in_cad, const KdTree& model_tree,
                                   const std::vector<Vec3>& model_normals,
                                   const UncertaintySettings& settings = {},
                                   double pair_distance_mm = 2.0);

}  // namespace springscan::analysis
