#pragma once
// The deformation field at sub-sample accuracy (docs/matching.md "Refined field").
//
// The raw matching (deformation_field.hpp) pairs k-center points of model and scan, which are
// independent samplings with a covering radius w: a pair can be up to w apart along the surface
// whatever the part did. The refinement answers, for every model control point, where that
// material point lies in the scan:
//  1. predict it with the rigid motion of the material there (part_motion.hpp: the flange's
//     motion chained through the measured springback, blended across bend zones; without a
//     segmentation, the matching's displacement smoothed over its neighbours);
//  2. correct the prediction along the moved surface normal by the robust mean normal offset of
//     the scan points around the predicted position (within support_radius_mm along the surface
//     and normal_window_mm along the normal; on a bend, the offset is radial from the bend
//     axis, so the cylinder's curvature does not bias it);
//     along a direction no flange plane fixes (the bend lines of an extrusion), the scan's
//     sheet edges against the CAD's give the position;
//     on a curved face of neither flange nor bend (a hole wall), the CAD surface's height over
//     the tangent plane, from the samples' exact normals, is taken out of the offsets;
//  3. points with fewer than min_support_points scan points around them are not covered and
//     get no vector. On a solid the scanner sees each skin from outside the material only: a
//     scan point supports a control point only if its normal (when the scan has normals) lies
//     within 60 deg of the CAD normal expected where it lies (not the far skin, not a sheet
//     edge or hole wall beside a skin), and the window along the normal stays within half the
//     sheet thickness, so the far skin never supports a vector; a point whose material moves
//     through an unmeasured bend gets none either (docs/matching.md "Refined field", coverage).
// Each vector's uncertainty is the robust sigma of its support over sqrt(count).
//
// Thread safety: a pure function; the result does not depend on the thread count.

#include <vector>

#include "analysis/core/part_model.hpp"
#include "analysis/matching/deformation_field.hpp"
#include "analysis/springback/springback.hpp"

namespace springscan::analysis {

/// What the refinement reads besides the raw field. References must outlive the call.
struct FieldRefinementInput {
  const std::vector<Vec3>& model_points;   ///< the k-center control points, CAD frame
  const std::vector<Vec3>& model_normals;  ///< their sample normals
  const std::vector<int>& model_faces;     ///< their face ids (-1: unknown)
  const PartSegmentation& segmentation;
  const SpringbackResult* springback;      ///< the local fits and bend table; null: none
  const std::vector<Vec3>& scan_points;    ///< the whole scan in the result frame
  const std::vector<Vec3>& model_samples;  ///< all model samples (the sheet's edges)
  /// The scan's normals (result frame), pointing out of the material toward the sensor as the
  /// drivers and scanner files give them; null or empty: none (the far skin is then excluded by
  /// position alone).
  const std::vector<Vec3>* scan_normals = nullptr;
  /// The face id of every entry of `model_samples`; null or empty: none (a control point on a
  /// face of neither flange nor bend then takes the motion of the nearest control point that
  /// has one, instead of its own position's on the nearest flange or bend).
  const std::vector<int>* model_sample_faces = nullptr;
  /// Their exact normals; with the faces, the curvature of a hole wall or a rounded sheet edge
  /// is taken out of its normal offsets. Null or empty: those faces are taken as flat.
  const std::vector<Vec3>* model_sample_normals = nullptr;
  /// Where the scanner looked from (result frame). A scan of a solid without normals (the laser
  /// driver gives points only) gets them estimated here, for the scan points near the
  /// predictions only, turned toward this point; null: none estimated (position rule alone).
  const Vec3* scan_viewpoint = nullptr;
};

/// The refined field: `vectors` replaced by one refined vector per covered control point
/// (model_index kept; scan_index the raw partner, or UINT32_MAX), the raw pairs moved to
/// `matched`. With settings.enabled false the raw field is returned unchanged.
DeformationField refine_field(const DeformationField& raw, const FieldRefinementInput& input,
                              const FieldRefinementSettings& settings = {});

}  // namespace springscan::analysis
