#pragma once
// The measured cylinder of a bend zone (docs/springback.md "Bend radius"): the scan points of
// one side of the sheet on the bend, fitted by a circle whose centre moves linearly along the
// nominal axis (a cylinder whose axis may tilt a little, as it does where the springback
// varies along the bend): geometric least squares (Gauss-Newton on the distances to the axis),
// started from the algebraic (Kasa) circle, outliers beyond 3 robust sigmas left out.
//
// Thread safety: pure function.

#include <cstdint>
#include <span>

#include "analysis/core/point_cloud.hpp"

namespace springscan::analysis {

struct BendZoneSettings {
  int min_points = 50;          ///< fewer: not fitted
  int max_iterations = 20;      ///< Gauss-Newton steps
  double outlier_sigmas = 3.0;  ///< points farther from the cylinder are left out
};

struct BendZoneFit {
  bool fitted = false;
  double radius_mm = 0.0;  ///< of the scanned side of the sheet
  double rms_mm = 0.0;     ///< of the inliers' distances from the cylinder
  std::size_t inliers = 0;
  Vec3 axis_point = Vec3::Zero();       ///< the measured axis at the nominal axis point's position
  Vec3 axis_direction = Vec3::UnitX();  ///< unit, along the nominal direction
  Vec3 axis_step = Vec3::UnitX();       ///< the axis' move per mm along the nominal axis
  /// The measured axis where it crosses the plane `position_mm` along the nominal axis from the
  /// nominal axis point (perpendicular to the nominal axis).
  Vec3 axis_at(double position_mm) const { return axis_point + position_mm * axis_step; }
};

/// Fits the cylinder to `points` of `cloud` (CAD frame), with the nominal axis (`axis_point`,
/// unit `axis_direction`) as the frame.
BendZoneFit fit_bend_zone(const PointCloud& cloud, std::span<const std::uint32_t> points,
                          const Vec3& axis_point, const Vec3& axis_direction,
                          const BendZoneSettings& settings = {});

}  // namespace springscan::analysis
