#pragma once
// The rigid motion of every point of a bent part, from the springback stage (docs/matching.md
// "Refined field"). Each flange moves rigidly; the flanges are chained through the bends: the
// flange on the far side of a bend turns about the CAD bend axis by the measured springback
// (the bend opens), so one rigid motion per flange follows from the bend table alone, exact in
// the directions a plane fit cannot see (a slide in the flange's plane, a turn about its
// normal). One rigid correction G of the whole chain is then fitted to the flanges' local fits
// (each flange's measured plane), so the motions are in the result frame. Inside a bend zone a
// point at angular position t in [0, 1] (from flange a to flange b) turns by t times the bend's
// springback: the zone stays a cylinder tangent to both flanges (paper §5: "for the areas of the
// model shape between the subareas, the correspondences can be interpolated").
//
// Thread safety: pure functions; a PartMotion is immutable once built.

#include <vector>

#include "analysis/core/part_model.hpp"
#include "analysis/core/point_cloud.hpp"
#include "analysis/springback/springback.hpp"

namespace springscan::analysis {

/// The motion of each flange and how the bends blend them.
struct PartMotion {
  std::vector<Transform> flange;      ///< per segmentation flange (same order): T_result_cad
  std::vector<bool> flange_fitted;    ///< its local fit took part in G (fitted, chain measured)
  std::vector<double> bend_turn_rad;  ///< per segmentation bend: signed turn of b relative to a
                                      ///< about the bend axis (-springback)
  std::vector<int> face_flange;       ///< per face id: index of its flange, -1 if none
  std::vector<int> face_bend;         ///< per face id: index of its bend, -1 if none
  Transform correction = Transform::Identity();  ///< G, fitted to the local fits
  /// Translations no flange plane constrains (along the bend lines of an extrusion): G keeps
  /// the best fit's value there; field_prediction.cpp measures them at the sheet's edges.
  std::vector<Vec3> free_translations;
  /// Per flange: its motion rests on measurements only, every bend on its chain from the root
  /// measured. A flange reached through an unmeasured bend (its wall not seen, a closed hem)
  /// is placed as if that bend had not sprung back: a guess, exact in no direction its plane
  /// does not fix.
  std::vector<bool> flange_measured;
  std::vector<bool> bend_measured;  ///< per segmentation bend: the springback stage measured it
  int root_flange = -1;             ///< index of the flange the chain starts from (does not turn)
  bool usable = false;              ///< at least one flange was fitted
};

/// Builds the chained motions from the bend table and fits G to the flanges' local fits at
/// `points` (CAD frame, with their sample normals and face ids; the k-center control points).
PartMotion part_motion(const PartSegmentation& segmentation, const SpringbackResult& springback,
                       const std::vector<Vec3>& points, const std::vector<Vec3>& normals,
                       const std::vector<int>& face_ids);

/// Whether the motion of face `face_id` rests on measurements (its flange's, or for a bend face
/// both flanges' and the bend's); false for faces of neither.
bool motion_measured(const PartMotion& motion, const PartSegmentation& segmentation, int face_id);

/// The rigid motion (T_result_cad) of the material at CAD point `p` of face `face_id`: its
/// flange's, or for a bend face the blend by angular position. `std::nullopt`-like: returns
/// false when the face belongs to neither a flange nor a bend.
bool motion_at(const PartMotion& motion, const PartSegmentation& segmentation, const Vec3& p,
               int face_id, Transform& out);

}  // namespace springscan::analysis
