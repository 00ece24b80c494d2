#pragma once
// The shape of one flange as scanned (docs/springback.md "Beyond rigid flanges"): how far it is
// from a plane (flatness), how much it curls across its width (a signed radius, perpendicular
// to the bend line) and how much its plane turns along the bend line (twist), and the tangent
// plane at its end next to a bend, which NUMISHEET'93 measures a bend angle by on a curled wall.
//
// Model: in the flange's frame (s across, t along the bend line, h along the CAD normal, origin
// at the centroid of its points) the surface is the implicit circle-in-s family
//   A (s^2 + h^2) + (B + G t) s + (C + E t) - h = 0,
// a circle of curvature 2A / sqrt((B + G t)^2 + 1 - 4 A (C + E t)) in every section t (a plane
// when A = 0), its section turning by G / (1 + B^2) rad per mm along t. Linear least squares in
// (A, B, C, E, G), exact for a constant curl of any radius and for a linear twist of a flat
// flange, and well conditioned as A goes to 0 (a flat flange). Outliers: 3 robust sigmas.
//
// Thread safety: pure functions.

#include <cstdint>
#include <limits>
#include <span>
#include <vector>

#include "analysis/core/point_cloud.hpp"

namespace springscan::analysis {

struct FlangeShapeSettings {
  /// A curl is reported when its curvature exceeds this many standard errors...
  double curl_significance = 6.0;
  /// ...and bows the flange by at least this much from its chord across the points' width.
  /// 0.1 mm: at 0.02 mm noise a narrow wall (the demo bracket's 12 mm) fits a bow of 0.03-0.04
  /// mm from its noise and a little bend-zone leakage, and a false curl moves its bends' angles
  /// to the end tangents (0.6 deg off there); a rigid
  /// 45 deg side-panel flange of 8,500 points read as curled to 41 m at 0.03 mm.
  double min_curl_sagitta_mm = 0.1;
  double outlier_sigmas = 3.0;  ///< points farther from the model than this are left out
  int min_points = 50;          ///< fewer: the shape is not measured
  /// A flange whose points span less than this along the bend line has no twist (a short tab's
  /// twist is its noise).
  double min_twist_length_mm = 30.0;
};

/// A flange's frame: unit u (across, perpendicular to the bend line), d (along the bend line),
/// n (the CAD normal), right-handed (u = d x n); origin at the centroid of its points.
struct FlangeFrame {
  Vec3 origin = Vec3::Zero();
  Vec3 u = Vec3::UnitX();
  Vec3 d = Vec3::UnitY();
  Vec3 n = Vec3::UnitZ();
  Vec3 local(const Vec3& p) const {  ///< (s, t, h) of a CAD-frame point
    const Vec3 q = p - origin;
    return {q.dot(u), q.dot(d), q.dot(n)};
  }
};

/// The fitted surface (see the model above), in frame coordinates.
struct FlangeSurface {
  double A = 0.0, B = 0.0, C = 0.0, E = 0.0, G = 0.0;
};

struct FlangeShape {
  bool measured = false;
  FlangeFrame frame;
  FlangeSurface surface;           ///< A = 0 unless curled
  double inlier_threshold_mm = 0;  ///< |residual| beyond this: an outlier
  std::size_t inliers = 0;
  std::vector<Vec3> local;           ///< (s, t, h) of each point given to the fit, in order
  std::vector<std::uint8_t> inlier;  ///< per point given to the fit (same order): 1 = inlier
  double flatness_rms_mm = 0.0;      ///< rms distance of the inliers from their least-squares plane
  double flatness_max_mm = 0.0;      ///< largest such distance
  bool curled = false;               ///< false: flat within noise (curl_radius_mm is infinite)
  /// Signed radius of curl across the flange at its middle: positive when the centre of
  /// curvature lies on the side the CAD normal points to.
  double curl_radius_mm = std::numeric_limits<double>::infinity();
  /// Turn of the flange's normal, right-handed about the bend line, per 100 mm along it (a
  /// chirality: independent of the line's orientation).
  double twist_deg_per_100mm = 0.0;
  bool twist_measured = false;  ///< its points span min_twist_length_mm along the bend line
  /// Expanded uncertainties (k = 2; docs/uncertainty.md), filled by the uncertainty stage.
  double flatness_uncertainty_mm = 0.0;     ///< of flatness_max_mm
  double curl_radius_uncertainty_mm = 0.0;  ///< of curl_radius_mm, when curled
};

/// The frame of a flange with CAD normal `normal` and bend line direction `along` (projected
/// into the plane), origin at the centroid of `points` of `cloud`.
FlangeFrame flange_frame(const PointCloud& cloud, std::span<const std::uint32_t> points,
                         const Vec3& normal, const Vec3& along);

/// Fits the shape model to `points` of `cloud` (CAD frame). Fewer than min_points points (or
/// a degenerate spread) leave it unmeasured. `plane_rms_mm`: the rms of the flange's plane
/// fit, when there is one; a curl must fit its inliers no worse than that (a real curl fits
/// far better than the plane; stray points among a short tab's few bend a quadratic that fits
/// worse).
FlangeShape fit_flange_shape(const PointCloud& cloud, std::span<const std::uint32_t> points,
                             const FlangeFrame& frame, const FlangeShapeSettings& settings = {},
                             double plane_rms_mm = std::numeric_limits<double>::infinity());

/// The unit normal (near frame.n) of the tangent plane of `surface` at the point of its section
/// through `near` that lies closest to `near` (the bend axis next to the flange's end: on a
/// circle that is where the bend's arc meets it tangentially; on a plane it does not matter).
Vec3 end_normal(const FlangeFrame& frame, const FlangeSurface& surface, const Vec3& near);

/// Accumulates the points of one strip along the bend line and refits its section with the
/// flange's curvature held (so a short strip still gives the tangent at the end).
class StripFit {
 public:
  StripFit() = default;
  StripFit(const FlangeSurface& surface, double t_centre);
  void add(const Vec3& q);  ///< a point of the strip in frame coordinates (s, t, h)
  std::size_t points() const { return count_; }
  /// The strip's surface (A held, B and C refitted, E its slope along t about t_centre, G 0);
  /// false when the points do not determine it.
  bool solve(FlangeSurface& out) const;

 private:
  double A_ = 0.0, t_centre_ = 0.0;
  Eigen::Matrix3d normal_ = Eigen::Matrix3d::Zero();
  Eigen::Vector3d rhs_ = Eigen::Vector3d::Zero();
  std::size_t count_ = 0;
};

}  // namespace springscan::analysis
