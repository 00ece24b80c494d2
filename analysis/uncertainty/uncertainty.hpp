#pragma once
// The expanded uncertainty U (k = 2, about 95 %) of every value a tolerance decides
// (docs/uncertainty.md, issue 41), from the data of that very scan and the station's own terms,
// combined by the GUM (root sum of squares):
//   - each flange's own inlier points: the covariance of its plane (or, on a curled flange, of
//     its curl model) from the residual variance, the points' spread and count, propagated to
//     the tilt across each of its bends, and so to the bend angle, the springback, the angle at
//     each station (the strip's own points), the curl radius;
//   - the method's residual error where the part departs from the model: a residual above the
//     part's noise is a shape the plane does not follow, and tilts it as a whole (its error is
//     not shrunk by the point count);
//   - the station: scanner_sigma_mm (a floor under the noise the fits show), calibration_angle_deg
//     (angles), calibration_length_mm (lengths; and angles over the part's extent),
//     temperature_delta_k (uncorrected expansion of lengths).
// A value the scan fixes poorly gets a large U, never a small wrong one: a flange with few points,
// a narrow spread or a residual far above the noise propagates exactly that.
//
// Thread safety: pure functions.

#include <vector>

#include "analysis/deviation/deviation.hpp"
#include "analysis/springback/springback.hpp"

namespace springscan::analysis {

/// The station's terms (standard uncertainties unless named otherwise) and the coverage factor.
/// Unset (0): `springscan analyze` without settings; the data's own terms remain.
struct UncertaintySettings {
  double scanner_sigma_mm = 0.0;       ///< one scan point along the surface normal (a floor)
  double calibration_angle_deg = 0.0;  ///< the heads' calibration, as an angle
  double calibration_length_mm = 0.0;  ///< the heads' calibration over the part, as a length
  double temperature_delta_k = 0.0;    ///< the part's temperature off 20 degC, uncorrected (K)
  double expansion_per_k = 11.5e-6;    ///< the part's linear expansion coefficient (steel)
  double coverage_factor = 2.0;        ///< k of U = k u
  /// A direction of the result frame the surface leaves free (an extrusion's length) is fixed
  /// by the part's ends (registration/boundary) to about this (standard, mm).
  double free_direction_mm = 0.5;
};

/// The standard uncertainties of one bend and how they came about (degrees, mm).
struct BendBudget {
  double fit_deg = 0.0;      ///< both flanges' plane (or end tangent) tilt from their points
  double shape_deg = 0.0;    ///< residual above the noise: the method's error (model departure)
  double station_deg = 0.0;  ///< calibration terms
  double angle_deg = 0.0;    ///< combined standard uncertainty of the angle (and springback)
  double radius_mm = 0.0;    ///< combined standard uncertainty of the measured radius
  std::vector<double> station_angle_deg;  ///< combined, per BendStation
};

/// The standard uncertainties of one flange's shape values (mm).
struct FlangeBudget {
  double flatness_mm = 0.0;
  double curl_radius_mm = 0.0;  ///< 0 when not curled
  double edge_mm = 0.0;         ///< of each trim edge's largest move: noise, calibration, heat
  double spacing_mm = 0.0;      ///< the flange's point spacing (its edge line's own error)
};

struct UncertaintyResult {
  std::vector<BendBudget> bends;      ///< per SpringbackResult::bends (same order)
  std::vector<FlangeBudget> flanges;  ///< per SpringbackResult::flanges (same order)
  double noise_mm = 0.0;              ///< the part's point noise: median flange residual (or floor)
  double coverage_factor = 2.0;
};

/// The settings' first out-of-range field (named as in UncertaintySettings), or nothing.
std::optional<Error> validate(const UncertaintySettings& settings);

/// Standard uncertainties of every measured value of `springback`. `part_extent_mm`: the
/// diagonal of the scan's extent (the length a calibration's length error spreads over).
UncertaintyResult estimate_uncertainty(const SpringbackResult& springback, double part_extent_mm,
                                       const UncertaintySettings& settings = {});

struct FrameUncertainty;  // frame_uncertainty.hpp

/// Writes the expanded uncertainties (k u) of `u` into the contract fields of `springback`
/// (BendMeasurement, BendStation, FlangeShape, EdgeDeviation). A value not measured keeps 0.
/// `frame`: the result frame's (its move at each trim edge is part of the edge's U), if known.
void attach_uncertainty(const UncertaintyResult& u, SpringbackResult& springback,
                        const FrameUncertainty* frame = nullptr);

/// The part's point noise as the flange fits show it: the lower median of their inliers' rms
/// distance from their planes (mm; 0 without a measured flange).
double part_noise_mm(const SpringbackResult& springback);

/// The noise of the signed distances themselves (mm): 1.4826 MAD / sqrt 2 of the differences of
/// consecutive points (a scanner's points come line by line) that lie within `neighbour_mm` of
/// each other, where the surface's own deviation barely changes. 0 with fewer than 100 such
/// pairs (points in no order).
double neighbour_noise_mm(const std::vector<Vec3>& points, const std::vector<double>& signed_mm,
                          double neighbour_mm = 0.5);

/// How far outliers above the p95 of |d| (up to 2 % of the points: the scanner's share the
/// station is specified for) can raise it: the p95 less the 93rd percentile of `signed_mm`.
double p95_outlier_shift_mm(const std::vector<double>& signed_mm);

/// Writes the expanded uncertainties of the deviation statistics: the noise of one point
/// (`noise_mm`: part_noise_mm, or the global fit's residual), the result frame's standard
/// uncertainty of each statistic (`frame_p95_mm`, `frame_max_mm`: frame_statistic_sigma), the
/// outliers' shift of the p95 (`outlier_shift_mm`: p95_outlier_shift_mm), the calibration
/// length and the expansion over `part_extent_mm`.
void attach_deviation_uncertainty(double noise_mm, double frame_p95_mm, double frame_max_mm,
                                  double outlier_shift_mm, double part_extent_mm,
                                  const UncertaintySettings& settings,
                                  DeviationStatistics& statistics);

}  // namespace springscan::analysis
