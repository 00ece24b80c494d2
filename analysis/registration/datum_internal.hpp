#pragma once
// PRIVATE to analysis/registration/datum*.cpp: the feature measurements (datum_measure.cpp) and
// the datum frame solve (datum.cpp).

#include <string>
#include <vector>

#include "analysis/registration/datum.hpp"

namespace springscan::analysis::datum_detail {

/// The scan points near one datum, in the CAD frame of the current alignment.
struct FeaturePoints {
  std::vector<Vec3> points;
  std::vector<Vec3> normals;  ///< toward the scanner, or empty
};

/// One feature measured (method in datum.hpp step 1).
struct FeatureFit {
  bool measured = false;
  std::string failure;  ///< why not, for the error naming the datum
  /// Not measured, and the scan shows something else where the feature should be (a skin facing
  /// away on a pad, skin inside a hole's or slot's outline): evidence that the frame is wrong, not
  /// only that the scan lacks the feature (set by the capture round only).
  bool contradicted = false;
  Vec3 point = Vec3::Zero();   ///< the feature's point: pad foot, hole or slot centre, edge
  Vec3 normal = Vec3::Zero();  ///< pads: the plane's normal
  double diameter_mm = 0.0;    ///< holes: diameter; slots: width
  std::size_t points = 0;
  double rms_mm = 0.0;
  std::string measured_by;  ///< what of the feature the scan showed: "plane", "wall", "rim", ...
};

/// How far from the datum's point a scan point can be and still belong to its feature when the
/// feature is at most `band_mm` off the nominal.
double gather_radius(const Datum& datum, double band_mm);

/// Measures `datum` (thickness resolved) from `near` with features at most `band_mm` off.
FeatureFit measure_feature(const Datum& datum, const FeaturePoints& near, double band_mm,
                           const DatumAlignmentSettings& settings);

/// How far from the datum's point the capture round (wide search, `capture_mm` off) looks.
double capture_radius(const Datum& datum, double capture_mm);

/// The capture round's coarse measurement of `datum` (thickness resolved) from `near`, its
/// feature up to `capture_mm` off the nominal (and tilted up to a few degrees): a pad by the
/// dominant plane of its skin; a hole or slot by where its outline best fits the empty part of
/// the skin's occupancy (the skin's rim); an edge by the skin's end (datum_capture.cpp).
FeatureFit capture_feature(const Datum& datum, const FeaturePoints& near, double capture_mm,
                           const DatumAlignmentSettings& settings);

/// The rim of a hole or slot on the seen skin, its skin band `band_mm`, the outline within
/// `band_mm` of the nominal (a slot: its two straight edges). For the capture round's refinement.
FeatureFit measure_rim(const Datum& datum, const FeaturePoints& near, double band_mm,
                       const DatumAlignmentSettings& settings);

/// The skin's point spacing around `datum` (1 / sqrt(density) of the skin points facing its
/// normal within the annulus [r_in, r_out] about its point), or 0 when there are none.
double skin_spacing(const Datum& datum, const FeaturePoints& near, double band_mm, double r_in,
                    double r_out);

/// Two unit vectors completing `n` (unit) to a right-handed frame.
void complete_basis(const Vec3& n, Vec3& e1, Vec3& e2);

/// The directions `datum` fixes (unit, across its normal for all but pads).
std::vector<Vec3> fixed_directions(const Datum& datum);

}  // namespace springscan::analysis::datum_detail
