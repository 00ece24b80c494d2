#include "analysis/messages/springback_proto.hpp"

#include <cmath>

namespace springscan::analysis {
namespace {

void to_proto(const Vec3& v, v1::Vec3& out) {
  out.set_x(v.x());
  out.set_y(v.y());
  out.set_z(v.z());
}

void edge_to_proto(const EdgeDeviation& e, v1::EdgeDeviation& out) {
  out.set_kind(std::string(edge_kind_name(e.kind)));
  out.set_strips(e.strips);
  out.set_in_plane_mean(e.in_plane_mean_mm);
  out.set_in_plane_min(e.in_plane_min_mm);
  out.set_in_plane_max(e.in_plane_max_mm);
  out.set_across_mean(e.across_mean_mm);
  out.set_across_min(e.across_min_mm);
  out.set_across_max(e.across_max_mm);
  to_proto(e.direction, *out.mutable_direction());
  to_proto(e.outward, *out.mutable_outward());
  out.set_length_mm(e.length_mm);
  out.set_uncertainty_mm(e.uncertainty_mm);
  out.set_in_plane_uncertainty_mm(e.in_plane_uncertainty_mm);
  out.set_across_uncertainty_mm(e.across_uncertainty_mm);
  for (const Vec3& p : e.cad_edge) to_proto(p, *out.add_cad_edge());
  for (const Vec3& p : e.scan_edge) to_proto(p, *out.add_scan_edge());
}

// The flange's shape figures; curl and twist only where they are defined; its trim edges.
void shape_to_proto(const FlangeFit& flange, v1::Segment& s) {
  const FlangeShape& shape = flange.shape;
  s.set_shape_measured(shape.measured);
  if (!shape.measured) return;
  s.set_flatness_mm(shape.flatness_max_mm);
  s.set_flatness_rms_mm(shape.flatness_rms_mm);
  s.set_flatness_uncertainty_mm(shape.flatness_uncertainty_mm);
  if (shape.curled && std::isfinite(shape.curl_radius_mm)) {
    s.set_curl_radius_mm(shape.curl_radius_mm);
    s.set_curl_radius_uncertainty_mm(shape.curl_radius_uncertainty_mm);
  }
  if (flange.has_bend_line && shape.twist_measured)
    s.set_twist_deg_per_100mm(shape.twist_deg_per_100mm);
  for (const EdgeDeviation& e : flange.trim_edges) {
    edge_to_proto(e, *s.add_trim_edges());
    if (e.kind == EdgeKind::kFree) edge_to_proto(e, *s.mutable_edge_deviation_mm());
  }
}

// The angle along the bend, the end-tangent definition and the measured radius.
void bend_shape_to_proto(const BendMeasurement& m, v1::Bend& b) {
  if (m.zone.fitted) {
    b.set_measured_radius_mm(m.measured_radius_mm);
    b.set_zone_rms_mm(m.zone.rms_mm);
    b.set_radius_uncertainty_mm(m.radius_uncertainty_mm);
  }
  if (!m.measured) return;
  b.set_plane_angle_deg(m.plane_angle_deg);
  b.set_end_tangents(m.end_tangents);
  for (const BendStation& station : m.stations) {
    v1::BendStation& out = *b.add_angle_along_bend();
    out.set_position_mm(station.position_mm);
    out.set_angle_deg(station.angle_deg);
    out.set_springback_deg(station.springback_deg);
    out.set_angle_uncertainty_deg(station.angle_uncertainty_deg);
  }
  b.set_angle_min_deg(m.angle_min_deg);
  b.set_angle_max_deg(m.angle_max_deg);
  b.set_angle_spread_deg(m.angle_spread_deg);
  b.set_angle_twist_deg(m.angle_twist_deg);
}

}  // namespace

void to_proto(const LocalFitResult& fit, v1::LocalFit& out) {
  out.clear_transform();
  const Eigen::Matrix4d m = fit.T_model_subset.matrix();
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) out.add_transform(m(r, c));
  out.set_rms(fit.rms_mm);
  out.set_inliers(static_cast<std::int64_t>(fit.inliers));
  out.set_iterations(fit.iterations);
  out.set_converged(fit.converged);
  out.clear_error_history();
  for (double e : fit.error_history) out.add_error_history(e);
}

void fill_springback_report(const SpringbackResult& result, v1::InspectionReport& report) {
  for (const FlangeFit& flange : result.flanges) {
    v1::Segment& s = *report.add_segments();
    s.set_id(flange.flange_id);
    for (int face : flange.face_ids) s.add_cad_faces(face);
    s.set_points(static_cast<std::int64_t>(flange.indices.size()));
    if (flange.fitted) to_proto(flange.fit, *s.mutable_local_fit());
    s.set_kind("flange");
    shape_to_proto(flange, s);
  }
  for (const BendMeasurement& m : result.bends) {
    v1::Bend& b = *report.add_bends();
    b.set_id(m.bend_id);
    to_proto(m.axis_point, *b.mutable_axis_point());
    to_proto(m.axis_direction, *b.mutable_axis_direction());
    b.set_radius_mm(m.radius_mm);
    b.set_nominal_angle_deg(m.nominal_angle_deg);
    b.set_segment_a(m.flange_a);
    b.set_segment_b(m.flange_b);
    for (int face : m.face_ids) b.add_cad_faces(face);
    b.set_measured(m.measured);  // pass and angle_tolerance_deg: the verdict (verdict_proto.hpp)
    bend_shape_to_proto(m, b);
    b.set_measurable(m.measurable);
    b.set_status(m.status);
    if (!m.measured) continue;  // angles stay unset (0) when nothing was measured
    b.set_measured_angle_deg(m.measured_angle_deg);
    b.set_springback_deg(m.springback_deg);
    b.set_angle_uncertainty_deg(m.angle_uncertainty_deg);
    b.set_springback_uncertainty_deg(m.springback_uncertainty_deg);
  }
}

}  // namespace springscan::analysis
