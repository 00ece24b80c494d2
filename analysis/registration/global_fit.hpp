#pragma once
// Global registration (paper §3, DESIGN.md stage 4): PCA alignment with the axis ambiguity
// resolved (analysis/registration/pca.hpp), its distinct finalists compared on the full model by
// one converged robust error (analysis/registration/orientation.hpp), then ICP to convergence
// (analysis/registration/icp.hpp).

#include <optional>
#include <string>
#include <vector>

#include "analysis/core/expected.hpp"
#include "analysis/core/kdtree.hpp"
#include "analysis/core/part_model.hpp"
#include "analysis/registration/boundary.hpp"
#include "analysis/registration/icp.hpp"
#include "analysis/registration/orientation.hpp"
#include "analysis/registration/pca.hpp"

namespace springscan::analysis {

struct GlobalFitSettings {
  bool pca_initial_alignment = true;    ///< false: ICP starts from the identity (pre-aligned data)
  PcaAlignSettings pca;                 ///< candidate search
  double pca_model_divisions = 100.0;   ///< candidates are scored on the model voxel-reduced to
                                        ///< its box diagonal / this (0: the full model)
  double symmetry_warning_ratio = 0.9;  ///< the orientation is ambiguous (warned, reported)
                                        ///< when the best orientation's robust error / the next
                                        ///< distinct one's exceeds this
                                        ///< (OrientationChoice::ambiguity), (0, 1]
  OrientationSettings orientation;      ///< the finalists compared on the full model
  IcpSettings icp;                      ///< the final ICP
  int exact_iterations = 3;  ///< then at most this many updates paired on the exact CAD surface,
                             ///< where the samples are biased (0: none; the pipeline's)
  /// The pose chosen, at most this many least-squares updates (finish_best_fit; the pipeline's),
  /// leaving out this share of the farthest pairs (outliers beyond the correspondence distance
  /// are left out and the Huber kernel bounds the rest). 0: the paper's best fit, the least
  /// squares over the whole seen surface. A share trimmed there is the most deformed surface,
  /// not outliers: 10 % pulled the frame of a U profile with 2.5 deg of springback 0.35 mm
  /// toward its unsprung part (docs/alignment.md, "The best fit of a sprung part").
  int final_iterations = 10;
  double final_trimmed_fraction = 0.0;
  std::size_t exact_points = 20'000;  ///< the exact-surface updates run on this many of the
                                      ///< scan's own points (strided; the pipeline picks them)
  BoundarySettings boundary;          ///< free directions fixed by the part's ends (pipeline)
};

struct GlobalFitResult {
  Transform T_cad_scan = Transform::Identity();  ///< maps scan coordinates into the CAD frame
  double rms_initial_mm = 0.0;        ///< rms nearest distance of the scan points as given, the
                                      ///< farthest icp.trimmed_fraction left out (outliers); over
                                      ///< an evenly strided sample of at most 4096 scan points
  double rms_after_pca_mm = 0.0;      ///< the same after the pure PCA alignment (paper Figure 5)
  double rms_final_mm = 0.0;          ///< the same after ICP
  IcpResult icp;                      ///< history, iterations, inliers, converged, stop reason
  PcaAlignResult pca;                 ///< candidate scores (empty when PCA was off)
  OrientationChoice orientation;      ///< the PCA finalists compared on the full model
  bool ambiguous = false;             ///< two distinct orientations fit within noise of each
                                      ///< other (and the model is not symmetric between them)
  std::vector<std::string> warnings;  ///< e.g. a near-symmetric part, a degenerate surface
};

/// Fits `scan` to the model given by `model_tree` (+ unit normals for point-to-plane).
/// `scan_normals` (one per scan point, facing the scanner; zero where unknown) turn on the
/// facing rule for a solid model seen from one side (analysis/registration/facing.hpp): every
/// pair and score then takes model samples facing the point's way only. Empty: nearest samples.
/// Errors: empty, non-finite or degenerate (collinear) clouds, invalid settings, normals of the
/// wrong count.
Expected<GlobalFitResult> global_fit(const std::vector<Vec3>& scan, const KdTree& model_tree,
                                     const std::vector<Vec3>& model_normals,
                                     const GlobalFitSettings& settings = {},
                                     const std::vector<Vec3>& scan_normals = {});

/// The global fit's final ICP from `start`: the facing rule with `scan_normals` (one per scan
/// point), nearest pairs without. global_fit ends with it; registration/orientation_settle.hpp
/// takes a rival orientation as far.
Expected<IcpResult> final_icp(const std::vector<Vec3>& scan, const KdTree& model_tree,
                              const std::vector<Vec3>& model_normals, const Transform& start,
                              const GlobalFitSettings& settings,
                              const std::vector<Vec3>& scan_normals = {});

/// `fit` continued from its pose by at most `iterations` ICP updates (`trimmed_fraction` of the
/// farthest pairs left out, the rest as settings.icp) on `scan`, with `scan_normals` one per point
/// for the facing rule, or empty. With `exact` (not null), the pairs are the exact CAD surface's
/// closest points and normals, and `scan` is the caller's sample of the scan's own points (the
/// pipeline's is settings.exact_points of them, evenly strided): a sample's tangent plane lies
/// off the surface by about d^2 / 2R at a distance d from a radius R, always toward the convex
/// side; at a closed hem's 0.05 mm fold that biased the cover flange's fit by 0.16 deg and
/// 0.16 mm (docs/alignment.md). The scan's own points, not the fit's voxel centroids: on a
/// solid scanned all round a voxel holds both skins, and its centroid lies mid-sheet. Without
/// `exact`, the pairs are the model samples' (final_icp), and `scan` the fit's points. `fit` then
/// has the new pose, inliers and stop, and the iterations and error history of both. Errors:
/// ICP's.
std::optional<Error> finish_best_fit(const std::vector<Vec3>& scan,
                                     const std::vector<Vec3>& scan_normals,
                                     const SurfaceDistance* exact, const KdTree& model_tree,
                                     const std::vector<Vec3>& model_normals,
                                     const GlobalFitSettings& settings, int iterations,
                                     double trimmed_fraction, IcpResult& fit);

/// Root mean square nearest distance of T * points to the tree, mm, over the closest
/// (1 - trimmed_fraction) of the points (parallel, deterministic).
double rms_nearest_distance(const std::vector<Vec3>& points, const Transform& T, const KdTree& tree,
                            double trimmed_fraction = 0.0, int threads = 0);

}  // namespace springscan::analysis
