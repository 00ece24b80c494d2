#pragma once
// The deformation field (paper section 5): vectors from model points to their corresponding
// scan points, over the k-center-reduced model and scan (both reduced with the same w, scan
// already registered into the CAD frame).
//
// Two ways to pair them:
//  * nearest neighbour, as the last ICP iteration does: each scan point picks its nearest model
//    point; model points nobody picks stay without a vector (the paper's Figure 9a), and edges
//    are mismatched when a flange has moved;
//  * the minimum-cost one-to-one matching (equation (3), assignment_points.hpp): every point of
//    the smaller set gets a distinct partner, so the field covers the model and edge points map
//    to edge points (Figure 9b, Figure 10).
//
// Thread safety: pure functions.

#include <cstddef>
#include <cstdint>
#include <vector>

#include "analysis/core/expected.hpp"
#include "analysis/core/point_cloud.hpp"
#include "analysis/matching/assignment_points.hpp"

namespace springscan::analysis {

enum class CorrespondenceMethod {
  kNearestNeighbor,  ///< each scan point to its nearest model point (ICP pairing)
  kMinCostMatching,  ///< exact minimum sum of squared distances, one-to-one
};

/// "nearest_neighbor" or "min_cost_matching" (the report's deformation_field.method).
const char* to_string(CorrespondenceMethod method);

/// How the raw matching is refined to sub-sample accuracy (field_refinement.hpp).
struct FieldRefinementSettings {
  bool enabled = true;              ///< false: the field is the raw pairing (paper §5 as printed)
  double support_radius_mm = 1.5;   ///< scan points within this (along the surface) of the
                                    ///< predicted position support a vector
  double normal_window_mm = 0.5;    ///< and within this along the normal (other side of the
                                    ///< sheet, outliers and other surfaces are farther)
  int min_support_points = 8;       ///< fewer: the point is not covered by the scan
  double outlier_mad_factor = 3.0;  ///< residuals beyond this many robust sigmas are dropped
  int threads = 0;                  ///< 0: all cores (the result does not depend on it)
};

struct DeformationFieldSettings {
  CorrespondenceMethod method = CorrespondenceMethod::kMinCostMatching;  ///< pairing rule
  PointMatchingSettings matching;      ///< solver settings for kMinCostMatching
  FieldRefinementSettings refinement;  ///< sub-sample refinement of the pairing
};

/// One vector of the field: model point -> scan point, CAD frame, mm.
struct DeformationVector {
  std::uint32_t model_index = 0;  ///< index into the reduced model
  std::uint32_t scan_index = 0;   ///< index into the reduced scan
  Vec3 model = Vec3::Zero();
  Vec3 scan = Vec3::Zero();
  double squared_distance_mm2 = 0.0;
  double uncertainty_mm = 0.0;  ///< refined: 1-sigma of `scan` along the surface normal, from
                                ///< the local noise and the number of supporting scan points
  int support_points = 0;       ///< refined: scan points the normal offset was averaged over
  Vec3 displacement() const { return scan - model; }
};

struct DeformationField {
  CorrespondenceMethod method = CorrespondenceMethod::kMinCostMatching;
  std::vector<DeformationVector> vectors;  ///< at most one per model point, by model index
  std::size_t model_points = 0;
  std::size_t scan_points = 0;
  double coverage = 0.0;                   ///< share of model points with a vector (method)
  double nearest_neighbor_coverage = 0.0;  ///< the same share for nearest neighbour (paper 9a)
  double total_cost_mm2 = 0.0;             ///< sum of squared lengths of the vectors
  bool optimality_certified = false;       ///< matching: the global dual certificate held
  PointMatching matching;                  ///< solver statistics (matching only)
  /// Refined fields: the raw pairs that seeded them (the paper's field, kept for the report's
  /// deformation_field.matching[]); `vectors` then hold the refined vectors.
  std::vector<DeformationVector> matched;
  bool refined = false;
  std::vector<std::uint32_t> uncovered;  ///< refined: model points the scan does not cover
  std::vector<Vec3> uncovered_points;    ///< their positions (CAD frame)
  /// refined, solids: of `uncovered`, those the scan around them saw from the other side of the
  /// material only (its normals point into the sheet there)
  std::size_t seen_from_far_side = 0;
  /// refined: of `uncovered`, those the scan covers but whose material's motion rests on an
  /// unmeasured bend (part_motion.hpp motion_measured): the scan fixes the normal component only
  std::size_t unmeasured_motion = 0;
  /// refined: translations (CAD frame, unit) that neither a fitted flange's plane nor the scan's
  /// sheet edges measure; the field's component along them is the best fit's placement
  std::vector<Vec3> translations_from_fit;
  double scan_coverage = 0.0;    ///< refined: share of model points with a vector
  double residual_rms_mm = 0.0;  ///< refined: rms of the supporting scan points' normal
                                 ///< distance to the refined field's surface
};

/// Nearest-neighbour pairing: every scan point picks its nearest model point; each model point
/// picked at least once gets one vector, to the closest scan point that picked it. Sorted by
/// model index. O((n + m) log m).
std::vector<DeformationVector> nearest_neighbor_vectors(const std::vector<Vec3>& model,
                                                        const std::vector<Vec3>& scan);

/// The field by the chosen method; the nearest-neighbour coverage is always filled for
/// comparison. Errors: a non-finite coordinate, bad matching settings.
Expected<DeformationField> deformation_field(const std::vector<Vec3>& model,
                                             const std::vector<Vec3>& scan,
                                             const DeformationFieldSettings& settings = {});

}  // namespace springscan::analysis
