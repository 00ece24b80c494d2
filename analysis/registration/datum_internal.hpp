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
  std::string failure;         ///< why not, for the error naming the datum
  Vec3 point = Vec3::Zero();   ///< the feature's point: pad foot, hole or slot centre, edge
  Vec3 normal = Vec3::Zero();  ///< pads: the plane's normal
  double diameter_mm = 0.0;    ///< holes: diameter; slots: width
  std::size_t points = 0;
  double rms_mm = 0.0;
};

/// How far from the datum's point a scan point can be and still belong to its feature when the
/// feature is at most `band_mm` off the nominal.
double gather_radius(const Datum& datum, double band_mm);

/// Measures `datum` (thickness resolved) from `near` with features at most `band_mm` off.
FeatureFit measure_feature(const Datum& datum, const FeaturePoints& near, double band_mm,
                           const DatumAlignmentSettings& settings);

/// Two unit vectors completing `n` (unit) to a right-handed frame.
void complete_basis(const Vec3& n, Vec3& e1, Vec3& e2);

/// The directions `datum` fixes (unit, across its normal for all but pads).
std::vector<Vec3> fixed_directions(const Datum& datum);

}  // namespace springscan::analysis::datum_detail
