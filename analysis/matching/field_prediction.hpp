#pragma once
// Step 1 of the field refinement (field_refinement.hpp): where every control point's material
// is predicted to lie, from the rigid motion of the material there. Internal to
// field_refinement.cpp.

#include <vector>

#include "analysis/matching/field_refinement.hpp"

namespace springscan::analysis {

/// The predicted motion of every control point.
struct FieldPrediction {
  std::vector<Transform> motion;  ///< T_result_cad of the material at the point
  std::vector<int> bend;          ///< bend index when the point lies in a bend zone, else -1
  std::vector<bool> guessed;      ///< the motion rests on an unmeasured bend (motion_measured)
  std::vector<Vec3> curvature;    ///< other faces: (a, b, c) of the CAD surface's height
                                  ///< h = (a x^2 + 2 b x y + c y^2) / 2 over the tangent plane
  /// Translations no fitted flange plane fixes that the sheet's edges did not measure either:
  /// along them the field keeps the best fit's value (DeformationField::translations_from_fit)
  std::vector<Vec3> translations_from_fit;
};

/// The tangent basis of a normal in which FieldPrediction::curvature is given.
inline void tangent_basis(const Vec3& n, Vec3& u, Vec3& v) {
  u = n.unitOrthogonal();
  v = n.cross(u);
}

/// The motion of every control point of `in`: the flange's motion chained through the measured
/// springback (part_motion.hpp), shifted along the directions no flange plane fixes by the
/// scan's sheet edges; a face of neither flange nor bend takes the motion of the material it
/// bounds. Without a segmentation, the raw matching's displacement smoothed over its
/// neighbours.
FieldPrediction predict_field(const DeformationField& raw, const FieldRefinementInput& in);

}  // namespace springscan::analysis
