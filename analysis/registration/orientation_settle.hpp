#pragma once
// The orientation choice settled on converged fits. The global fit compares its orientation
// candidates after short refinements (registration/orientation.hpp); along a direction the
// surface barely fixes (a long panel's length) those stop millimetres apart, and the wrong half
// turn of a near-symmetric part can score best by where its refinement happened to stop (the
// openamr side panel, zero springback: its right orientation 0.035 mm^2 at 4-12 mm off along its
// length, the half turn 0.032). So every distinct orientation that scored within settle_ratio of
// the best (and that the model does not map onto the best's by a symmetry of its own) is taken
// as far as the best: the final ICP, its updates on the exact surface and the boundary's pinning
// (registration/boundary.hpp). Then they are judged, in order: by the part catalogue's symmetry
// features, when those tell them apart; else by the decisive points, the scan points that one
// orientation leaves far off the surface and another fits (a notch or hole only one of them
// has; orientation_settle.cpp); else by the same error against the exact CAD surface on the
// same fit points (exact_surface_score), the lowest winning. Two that stay within noise of each
// other (symmetry_warning_ratio) make the part ambiguous, and a warning says what the scan lacked.
//
// Thread safety: a pure function.

#include <vector>

#include "analysis/core/expected.hpp"
#include "analysis/core/kdtree.hpp"
#include "analysis/core/part_model.hpp"
#include "analysis/registration/boundary.hpp"
#include "analysis/registration/global_fit.hpp"

namespace springscan::analysis {

struct OrientationSettleInput {
  const std::vector<Vec3>& fit_points;     ///< the global fit's scan points, scan frame
  const std::vector<Vec3>& fit_normals;    ///< one per fit point (facing rule), or empty
  const std::vector<Vec3>& scan;           ///< the whole scan, scan frame (the boundary's ends)
  const std::vector<Vec3>& exact_points;   ///< the exact-surface updates' scan points ...
  const std::vector<Vec3>& exact_normals;  ///< ... and their normals (one each), or empty
  const PartModel& model;                  ///< with its exact distance; without, nothing is settled
  const KdTree& model_tree;                ///< over model.samples.points
  /// The exact distance when the global fit ended with its updates on the exact surface
  /// (finish_best_fit), so that the rivals end alike; null: they did not.
  const SurfaceDistance* exact_updates = nullptr;
  /// `scan` prepared for the boundary once (the caller's, reused), or null: drawn per rival.
  const BoundaryScan* boundary_scan = nullptr;
};

/// Settles `fit`'s orientation (see above). `pinned`: the boundary's result for fit.T_cad_scan.
/// Returns the boundary result of the orientation chosen; `fit` then describes it: T_cad_scan
/// (pinned), icp, rms_final_mm, orientation.best, the settled candidates' score_mm2 (their
/// converged exact scores), orientation.ambiguity and ambiguous, fit.ambiguous and its warning.
/// Without a rival (or an exact distance) returns `pinned` and leaves `fit` as it is.
Expected<BoundaryResult> settle_orientation(const OrientationSettleInput& in,
                                            const GlobalFitSettings& settings, GlobalFitResult& fit,
                                            BoundaryResult pinned);

}  // namespace springscan::analysis
