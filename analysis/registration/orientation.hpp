#pragma once
// The orientation choice of the global fit, for near-symmetric parts: the PCA search's distinct
// finalists are each refined on the same scan points against the full model, by the same ICP, and
// then compared on the same (larger) set of scan points by the same robust error. A surface
// distance alone cannot see a flange that overhangs the model's end (it lies in the flange's
// plane), so the error is the distance to the nearest sample's tangent plane plus how far the point
// lies beyond the sample spacing from that sample, capped so that outliers weigh the same for every
// candidate. Two distinct orientations whose errors are within noise of each other make the
// part ambiguous, unless the model maps onto itself by the motion between them (a symmetric CAD
// part: the two are the same answer).

#include <cstddef>
#include <vector>

#include "analysis/core/expected.hpp"
#include "analysis/core/kdtree.hpp"
#include "analysis/registration/icp.hpp"

namespace springscan::analysis {

struct OrientationSettings {
  std::size_t refine_points = 1000;    ///< scan points (evenly strided) each finalist is refined on
  int refine_iterations = 15;          ///< ICP updates per finalist against the full model, at most
  std::size_t score_points = 4000;     ///< scan points (evenly strided) every finalist is scored on
  double score_cap_mm = 1.0;           ///< a point's error counts at most this much (outliers)
  double spacing_allowance = 3.0;      ///< a point may lie this many median model sample
                                       ///< spacings from its nearest sample before that distance
                                       ///< counts (random samples leave gaps; an overhang is
                                       ///< farther)
  double ambiguous_error_ratio = 0.9;  ///< ambiguous when best / next distinct orientation's
                                       ///< mean squared error exceeds this, (0, 1]
  double distinct_pose_deg = 5.0;      ///< orientations farther apart than this are distinct
  double equivalent_rms_mm = 0.02;     ///< the model moved by the motion between two finalists
                                       ///< (centroid kept, refined onto itself) fits itself
                                       ///< within this robust rms: a symmetric model, the two
                                       ///< orientations are the same answer
};

struct OrientationCandidate {
  Transform T_cad_scan = Transform::Identity();  ///< after its refinement
  double score_mm2 = 0.0;                        ///< mean squared capped robust error
};

struct OrientationChoice {
  std::vector<OrientationCandidate> candidates;  ///< as given, refined and scored
  std::size_t best = 0;                          ///< index of the lowest score (lowest on ties)
  double ambiguity = 0.0;  ///< best score / the next distinct, non-equivalent orientation's
                           ///< (0 when there is none): near 1 = the scan cannot tell them apart
  bool ambiguous = false;  ///< ambiguity > ambiguous_error_ratio
  bool symmetric_model = false;  ///< a distinct orientation fits as well and the model maps onto
                                 ///< itself by the motion between them (equivalent)
};

/// Refines every start (at least one) on the same scan sample against `model_tree`, scores all on
/// the same scan sample and picks the best. `icp_settings` is the refinement's engine setup
/// (max_iterations is replaced by refine_iterations). With `scan_normals` (one per scan point: a
/// one-sided scan of a solid) pairs and scores follow the facing rule
/// (analysis/registration/facing.hpp). Errors: no start, empty clouds, normals of the wrong count.
Expected<OrientationChoice> choose_orientation(
    const std::vector<Vec3>& scan, const KdTree& model_tree, const std::vector<Vec3>& model_normals,
    const std::vector<Transform>& starts, const OrientationSettings& settings,
    const IcpSettings& icp_settings, int threads = 0, const std::vector<Vec3>& scan_normals = {});

/// The mean squared capped robust error of T * points against the model (tangent-plane distance
/// to a sample, plus the distance beyond `spacing_mm` from it, the least over the 4 nearest
/// samples), mm^2. Serial.
double robust_surface_score(const std::vector<Vec3>& points, const Transform& T,
                            const KdTree& model_tree, const std::vector<Vec3>& model_normals,
                            double spacing_mm, double cap_mm);

/// The median distance between a model sample and its nearest other sample (over a strided
/// subset), mm.
double model_sample_spacing(const KdTree& model_tree);

}  // namespace springscan::analysis
