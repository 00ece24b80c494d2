#pragma once
// The deformation field at arbitrary points (the compensated CAD's face samples, docs/matching.md
// "Compensated CAD"): a local linear fit of the field's vectors around each point.
//
// d(x) = a, where (a, B) minimise sum_i w_i |d_i - a - B (p_i - x)|^2 over the vectors with
// |p_i - x| <= 3 sigma, w_i = exp(-|p_i - x|^2 / (2 sigma^2)). Unlike the Gaussian average of
// compensation.hpp it reproduces a linear field exactly (a flange that turns about a bend axis)
// also at a free edge, where every neighbour lies on one side. The gradient B is held towards 0
// (a small ridge term) along directions the neighbours do not span, e.g. the normal of a flat
// flange. A point with no vector within 3 sigma is not covered.
//
// How well the field is known there: the weighted rms of the vectors about that fit (their
// noise, and near a bend line the kink a linear fit cannot follow). It is not divided by the
// number of vectors: near a bend line the error of d(x) is a bias of about that size, not noise
// that averages out. The compensated CAD tolerates this much scatter before a plane or cylinder
// gives way to a B-spline (compensated_solid.hpp).
//
// Thread safety: a pure function.

#include <vector>

#include "analysis/core/point_cloud.hpp"
#include "analysis/matching/deformation_field.hpp"

namespace springscan::analysis {

struct FieldEvaluationSettings {
  double smoothing_radius_mm = 0.0;  ///< sigma; 0: spacing_factor x the median point spacing
  double spacing_factor = 1.0;       ///< sigma per median point spacing when not given
  /// Unit directions the scan's surface does not fix (the report's global_fit.free_directions:
  /// a profile's length): d's component along each is dropped. Along them the field holds the
  /// alignment's choice (the part's ends, noise on a narrow end face), not a form error, and a
  /// die moved by it drifts and tilts its end faces round after round.
  std::vector<Vec3> free_directions;
};

struct FieldAtPoints {
  std::vector<Vec3> deformation;     ///< d at each point (zero where not covered), mm
  std::vector<bool> covered;         ///< a field vector lies within 3 sigma
  std::vector<int> support;          ///< field vectors within 3 sigma
  std::vector<double> spread_mm;     ///< weighted rms of the vectors about the fit (0: uncovered)
  double smoothing_radius_mm = 0.0;  ///< sigma used
};

/// The field at `points` (CAD frame). An empty field covers nothing.
FieldAtPoints evaluate_field(const DeformationField& field, const std::vector<Vec3>& points,
                             const FieldEvaluationSettings& settings = {});

}  // namespace springscan::analysis
