#pragma once
// Springback per bend by automatic multiple local best fits (paper section 4, automated as its
// outlook proposes; docs/springback.md). The scan is already in the CAD frame (after the global
// fit). Scan points are assigned to CAD flanges by their nearest model sample, leaving out a
// margin around every bend; each flange is fitted to the whole model on its own (local_fit);
// each bend's measured angle comes from the relative rotation of the two flanges it joins.
//
// Angle convention: the bend angle is the angle the sheet turns at the bend, i.e. the angle
// between the two flanges' normals (0 = flat). springback = nominal - measured: positive when
// the bend opened up.

#include <cstdint>
#include <string>
#include <vector>

#include "analysis/core/expected.hpp"
#include "analysis/core/part_model.hpp"
#include "analysis/core/point_cloud.hpp"
#include "analysis/springback/bend_zone.hpp"
#include "analysis/springback/flange_edge.hpp"
#include "analysis/springback/flange_shape.hpp"
#include "analysis/springback/local_fit.hpp"
#include "analysis/springback/relative_rotation.hpp"

namespace springscan::analysis {

/// Beyond rigid flanges: flange shape, bend radius, angle along the bend (bend_shape.cpp).
struct BendShapeSettings {
  FlangeShapeSettings flange;        ///< flatness, curl, twist per flange
  FlangeEdgeSettings edge;           ///< free edge of an end flange against the CAD edge
  BendZoneSettings zone;             ///< the bend zone's cylinder (measured radius)
  double station_spacing_mm = 20.0;  ///< angle along the bend: one station per this length
  int min_stations = 3;              ///< ...and at least this many
  int min_points_per_station = 30;   ///< a flange strip with fewer points leaves its station out
};

struct SpringbackSettings {
  LocalFitSettings local_fit;  ///< each flange's local best fit (threads: see below)
  BendShapeSettings shape;     ///< flange shape, bend radius, angle along the bend
  /// Flange samples this close to a bend are left out: at most this, less on a short flange
  /// (bend_margin_fraction of its depth from its bends), never below min_bend_margin_mm.
  double bend_margin_mm = 2.0;
  double bend_margin_fraction = 0.2;    ///< of the flange's depth from its nearest bend axis
  double min_bend_margin_mm = 0.5;      ///< the margin's floor (bend zone, noise, alignment)
  double assignment_distance_mm = 5.0;  ///< scan points farther from the model are left out
  double assignment_normal_deg = 30.0;  ///< with scan normals: a point takes the nearest model
                                        ///< sample whose normal is within this of its own
  /// Fewer points: not fitted, its bends are not measured. The floor of a plane fit with
  /// outlier rejection; whether a fitted flange fixes its bend angle is max_angle_sigma_deg's.
  int min_points_per_flange = 50;
  /// A bend whose angle the two flanges' points fix less well than this (one standard
  /// deviation, from each fit's noise and its points' spread across the bend) is not measured,
  /// with its figures: a short tab, or one the scan sees little of. 0 = off.
  double max_angle_sigma_deg = 0.05;
  /// A flange with fewer thinned points than this takes about this many more from the full
  /// scan: thinning is for large flanges, a short tab needs every point. 0 = off.
  std::int64_t dense_flange_points = 2000;
  /// A flange fit whose rms exceeds this x the median rms of the part's flange fits is not a
  /// plane of the scan (points of other faces, a skin it cannot see): not fitted, with its
  /// figures. The median is the scan's noise as the fits see it. 0 = off.
  double max_fit_rms_ratio = 5.0;
  double hem_angle_deg = 175.0;  ///< bends at least this sharp are closed hems: not measurable
  /// The scan is thinned by a fixed stride to at most this many points (0: every point).
  std::int64_t max_scan_points = 100000;
  /// Worker threads, 0 = all cores (overrides local_fit.threads); the result does not depend
  /// on it.
  int threads = 0;
};

/// One flange's points and local best fit.
struct FlangeFit {
  int flange_id = -1;
  std::vector<int> face_ids;
  std::vector<std::uint32_t> indices;  ///< scan points assigned to the flange
  bool fitted = false;
  std::string status;  ///< why it was not fitted, or empty
  LocalFitResult fit;
  Vec3 measured_normal = Vec3::Zero();  ///< normal of the fitted plane in the CAD frame
  double margin_mm = 0.0;               ///< the bend margin its samples were labelled with
  Vec3 centroid = Vec3::Zero();         ///< of its points (CAD frame)
  Mat3 spread = Mat3::Zero();           ///< sum of (p - centroid)(p - centroid)^T, mm^2
  FlangeShape shape;                    ///< flatness, curl, twist (shape.measured: whether)
  bool has_bend_line = false;  ///< false: no bend orients it; curl and twist are not defined
  /// Its measured trim edges against the CAD's (an end flange's free edge among them).
  std::vector<EdgeDeviation> trim_edges;
  /// The free edge of an end flange (one bend), when it was measured; else null.
  const EdgeDeviation* free_edge() const {
    for (const EdgeDeviation& e : trim_edges)
      if (e.kind == EdgeKind::kFree) return &e;
    return nullptr;
  }
};

/// The bend angle at one station along the bend line.
struct BendStation {
  double position_mm = 0.0;  ///< along axis_direction from axis_point (CAD frame)
  double angle_deg = 0.0;    ///< measured angle there
  double springback_deg = 0.0;
  double angle_uncertainty_deg = 0.0;  ///< expanded (k = 2), analysis/uncertainty
};

/// One bend: nominal geometry from the CAD, measured angle from the local fits. Whether it
/// passes is the verdict's decision (analysis/inspection/verdict.hpp), against its tolerance.
struct BendMeasurement {
  int bend_id = -1;
  int flange_a = -1;  ///< Flange::id
  int flange_b = -1;  ///< Flange::id
  std::vector<int> face_ids;
  Vec3 axis_point = Vec3::Zero();       ///< nominal bend axis, CAD frame
  Vec3 axis_direction = Vec3::UnitX();  ///< unit, oriented so the nominal turn a -> b is positive
  double radius_mm = 0.0;
  double nominal_angle_deg = 0.0;
  double measured_angle_deg = 0.0;
  double springback_deg = 0.0;  ///< nominal - measured; > 0: the bend opened up
  AxisAngle relative_rotation;  ///< flange b relative to flange a, CAD frame (paper §4)
  Vec3 measured_axis_direction = Vec3::Zero();  ///< line of the two fitted planes, CAD frame
  bool measured = false;                        ///< false when a flange could not be fitted
  /// One standard deviation of the measured angle from the fits' noise and their points'
  /// spread across the bend (0 when not fitted).
  double angle_sigma_deg = 0.0;
  std::string status;  ///< why it was not measured, or empty
  /// The angle between the two flanges' fitted planes (paper section 4). It is the measured
  /// angle unless a flange is curled; then the measured angle is the one between the tangent
  /// planes at the flanges' ends next to the bend (NUMISHEET'93), and end_tangents is true.
  double plane_angle_deg = 0.0;
  bool end_tangents = false;
  std::vector<BendStation> stations;  ///< the angle along the bend, in position order
  double angle_min_deg = 0.0;         ///< over the stations
  double angle_max_deg = 0.0;
  double angle_spread_deg = 0.0;    ///< max - min
  double angle_twist_deg = 0.0;     ///< last station's angle - first's
  BendZoneFit zone;                 ///< the bend zone's cylinder, one side of the sheet
  double measured_radius_mm = 0.0;  ///< inner radius from the zone (zone.fitted: whether)
  /// False for a closed hem (nominal >= hem_angle_deg): its folded flange lies on the sheet,
  /// a flange fit cannot tell its springback; listed, never failing the part by itself.
  bool measurable = true;
  /// Expanded uncertainties (k = 2, about 95 %; docs/uncertainty.md): this scan's fits and the
  /// station's terms. Filled by the uncertainty stage; 0 until it ran.
  double springback_uncertainty_deg = 0.0;
  double angle_uncertainty_deg = 0.0;  ///< of measured_angle_deg
  double radius_uncertainty_mm = 0.0;  ///< of measured_radius_mm
};

struct SpringbackResult {
  std::vector<FlangeFit> flanges;  ///< in segmentation order
  std::vector<BendMeasurement> bends;
  std::size_t points_used = 0;  ///< scan points after thinning
  std::size_t thinning_stride = 1;
};

/// The signed angle (degrees) from u to v about `axis`.
double turn_deg(const Vec3& u, const Vec3& v, const Vec3& axis);

/// The flange's unit normal on the concave side of `bend` (the side facing its centre of
/// curvature), decided from where the flange's reference face lies relative to the axis.
Vec3 concave_normal(const Flange& flange, const Bend& bend);

/// An angle difference wrapped into (-180, 180] degrees.
double wrapped_deg(double a);

/// The bend angle (degrees) between two flanges as the data show it: the angle from normal_a
/// to D * normal_b, D = relative_rotation_matrix(T_model_a, T_model_b) (flange b relative to
/// flange a in the data, CAD frame), positive about `axis`. It equals the angle between the
/// two fitted planes, so it does not change when either fit is composed with a turn about its
/// own flange normal or a slide in its plane: the motions a plane fit cannot determine.
double measured_bend_angle_deg(const Vec3& normal_a, const Vec3& normal_b, const Vec3& axis,
                               const Transform& T_model_a, const Transform& T_model_b);

/// One bend from the local fits of its flanges `a` (of flange `fa`) and `b` (of `fb`): the
/// nominal turn between the flanges' normals taken on the bend's concave side (decided from
/// where each flange's reference face lies relative to the bend axis, so either side of the
/// sheet may be the reference), the measured turn after the relative rotation of the fits, and
/// springback = nominal - measured wrapped into (-180, 180]. A flange not fitted leaves the
/// bend unmeasured with a status. Pure function.
BendMeasurement measure_bend(const Bend& bend, const Flange& fa, const Flange& fb,
                             const FlangeFit& a, const FlangeFit& b);

/// Measures every bend of `model.segmentation` in `scan_in_cad`. A flange with too few points
/// (or a failed fit) leaves its bends unmeasured with a status; that is not an error.
/// Errors: model samples without normals or face ids, a bend naming an unknown flange, or
/// settings out of range.
Expected<SpringbackResult> measure_springback(const PartModel& model, const PointCloud& scan_in_cad,
                                              const SpringbackSettings& settings = {});

}  // namespace springscan::analysis
