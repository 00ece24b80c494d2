#pragma once
// The orientation choice of the global fit, for near-symmetric parts: the PCA search's distinct
// finalists are each refined on the same scan points against the full model, by the same ICP, and
// then compared on the same (larger) set of scan points by the same robust error. A surface
// distance alone cannot see a flange that overhangs the model's end (it lies in the flange's
// plane), so the error is the distance to the nearest sample's tangent plane plus how far the point
// lies beyond the sample spacing from that sample, capped so that outliers weigh the same for every
// candidate. Two distinct orientations whose errors are within noise of each other make the
// part ambiguous, unless the model maps onto itself by the motion between them (a symmetric CAD
// part: the two are the same answer). These are short refinements: a near-symmetric part's
// rivals are then compared on converged fits (registration/orientation_settle.hpp).

#include <cstddef>
#include <string>
#include <vector>

#include "analysis/core/expected.hpp"
#include "analysis/core/kdtree.hpp"
#include "analysis/core/part_model.hpp"
#include "analysis/registration/icp.hpp"

namespace springscan::analysis {

/// A region of the CAD where a near-symmetric part differs from its turned copy (a hole, a
/// notch, a tab at one end): rival orientations are judged there (orientation_settle.hpp). CAD
/// frame, mm.
struct SymmetryFeature {
  std::string name;
  Vec3 center = Vec3::Zero();
  double radius_mm = 0.0;
};

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
  double settle_ratio = 0.5;           ///< distinct orientations scoring within this of the best
                                       ///< (best / theirs above it) are tested for equivalence and
                                       ///< settled on converged fits
                                       ///< (registration/orientation_settle.hpp), (0, 1]
  std::vector<SymmetryFeature> symmetry_features;  ///< the part's, if any (part catalogue)
  std::size_t feature_points = 10000;    ///< scan points (evenly strided) judged in the features
  double feature_misfit_mm = 0.1;        ///< a point in a feature farther off the surface misfits,
  double feature_misfit_sigmas = 4.0;    ///< ... or farther than this many robust sigmas of the
                                         ///< fit's distances, when that is more
  std::size_t min_feature_misfits = 10;  ///< the features decide when the orientations' misfit
                                         ///< counts differ by at least this and the lower is at
                                         ///< most half the higher (a hole the other one fills)
  /// Decisive points (registration/orientation_settle.hpp): scan points (evenly strided) whose
  /// exact distance under every settled orientation is compared.
  std::size_t decisive_points = 100000;
  double decisive_margin_mm = 0.15;  ///< a point one orientation leaves this much farther off
  double decisive_sigmas = 6.0;      ///< the surface than the other (or this many robust
                                     ///< sigmas of all points' differences, when more) ...
  double decisive_far_ratio = 3.0;   ///< ... and at least this many times as far, tells
                                     ///< against it, by that difference up to:
  double decisive_cap_mm = 2.0;
  /// ... when another such point lies within this distance (mm): a notch or a hole the other
  /// orientation lacks shows as a patch of them, an outlier as a lone one. At sigma 0.05 mm with
  /// 2 % outliers, lone outliers that lay 3 times as far off one orientation as off the other
  /// outweighed a side panel's few notch points (4 against 8), leaving a good panel ambiguous.
  double decisive_company_mm = 2.0;
  /// An orientation wins when this many points tell against each other one (4: with the
  /// company rule, noise and outliers hardly tell, and 7-8 notch points are what some noisy
  /// side panel views show) ...
  std::size_t min_decisive_points = 4;
  double decisive_ratio = 0.25;     ///< ... and the evidence against it is at most this share of
                                    ///< theirs
  double distinct_pose_deg = 5.0;   ///< orientations farther apart than this are distinct
  double equivalent_rms_mm = 0.02;  ///< the model moved by the motion between two finalists
                                    ///< (centroid kept, refined onto itself) fits itself
                                    ///< within this robust rms: a symmetric model, the two
                                    ///< orientations are the same answer
};

struct OrientationCandidate {
  Transform T_cad_scan = Transform::Identity();  ///< after its refinement
  double score_mm2 = 0.0;                        ///< mean squared capped robust error
  bool equivalent = false;  ///< the model maps onto itself by the motion from the best to this
                            ///< (tested for candidates within settle_ratio of the best)
};

struct OrientationChoice {
  std::vector<OrientationCandidate> candidates;  ///< as given, refined and scored
  std::size_t best = 0;    ///< index of the lowest score (lowest on ties); on a symmetric model,
                           ///< of the one nearest the identity among it and its equivalents
  double ambiguity = 0.0;  ///< best score / the next distinct, non-equivalent orientation's
                           ///< (0 when there is none): near 1 = the scan cannot tell them apart
  bool ambiguous = false;  ///< ambiguity > ambiguous_error_ratio
  bool symmetric_model = false;  ///< a distinct orientation fits as well and the model maps onto
                                 ///< itself by the motion between them (equivalent)
  std::string decided_by = "surface";  ///< "surface", "converged surface", "decisive points" or
                                       ///< "symmetry features"
                                       ///< (orientation_settle.hpp)
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

/// The mean squared capped distance of T * points to the exact surface, mm^2. With `normals` (one
/// per point: a one-sided scan of a solid) a point whose closest surface faces against its turned
/// normal (the other skin) counts as cap_mm. Serial.
double exact_surface_score(const std::vector<Vec3>& points, const std::vector<Vec3>& normals,
                           const Transform& T, const SurfaceDistance& exact, double cap_mm);

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
