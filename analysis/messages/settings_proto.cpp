// Proto settings of the pre-processing, global fit and deviation stages (settings_proto.hpp).
#include "analysis/messages/settings_proto.hpp"

#include <cmath>
#include <optional>
#include <string>

namespace springscan::analysis {
namespace {

Error bad(const std::string& field, double value, const std::string& rule) {
  return fail(ErrorCode::kInvalidSettings,
              "settings: " + field + " = " + std::to_string(value) + " (" + rule + ")");
}

bool in_range(double v, double lo, double hi) { return std::isfinite(v) && v >= lo && v <= hi; }

// reduction.mesh_decimation: the fields given, then the stage's own range check (one place).
std::optional<Error> decimation_from_proto(const v1::MeshDecimationSettings& m,
                                           DecimationSettings& s) {
  if (m.has_enabled()) s.enabled = m.enabled();
  if (m.has_target_reduction()) s.target_reduction = m.target_reduction();
  if (m.has_feature_angle_deg()) s.feature_angle_deg = m.feature_angle_deg();
  if (m.has_boundary_vertex_deletion()) s.boundary_vertex_deletion = m.boundary_vertex_deletion();
  if (m.has_max_error_mm()) s.max_error_mm = m.max_error_mm();
  if (auto valid = validate(s); !valid) return valid.error();
  return std::nullopt;
}

}  // namespace

Expected<NormalSettings> from_proto(const v1::NormalSettings& m) {
  NormalSettings s;
  if (m.has_k_neighbors()) {
    if (m.k_neighbors() < 3 || m.k_neighbors() > 1000)
      return bad("normals.k_neighbors", m.k_neighbors(), "3 to 1000");
    s.k_neighbors = m.k_neighbors();
  }
  if (m.has_radius_mm()) {
    if (!in_range(m.radius_mm(), 0.0, 1e6)) return bad("normals.radius_mm", m.radius_mm(), ">= 0");
    s.radius_mm = m.radius_mm();
  }
  return s;
}

Expected<ReductionSettings> from_proto(const v1::ReductionSettings& m) {
  ReductionSettings s;
  if (m.has_kcenter_radius_mm()) {
    if (!in_range(m.kcenter_radius_mm(), 1e-6, 1e6))
      return bad("reduction.kcenter_radius_mm", m.kcenter_radius_mm(), "must be > 0");
    s.kcenter.radius_mm = m.kcenter_radius_mm();
  }
  if (m.has_kcenter_count()) {
    if (m.kcenter_count() < 0 || m.kcenter_count() > 10'000'000)
      return bad("reduction.kcenter_count", m.kcenter_count(), "0 to 10^7; 0 = use the radius");
    s.kcenter.center_count = static_cast<std::size_t>(m.kcenter_count());
  }
  if (m.has_voxel_size_mm()) {
    if (!in_range(m.voxel_size_mm(), 0.0, 1e6))
      return bad("reduction.voxel_size_mm", m.voxel_size_mm(), ">= 0; 0 = automatic");
    s.voxel_size_mm = m.voxel_size_mm();
  }
  if (m.has_min_curvature()) {
    if (!in_range(m.min_curvature(), 0.0, 1.0))
      return bad("reduction.min_curvature", m.min_curvature(), "0 to 1");
    s.curvature.min_curvature = m.min_curvature();
  }
  if (auto error = decimation_from_proto(m.mesh_decimation(), s.mesh_decimation)) return *error;
  return s;
}

namespace {

// The ICP fields of RegistrationSettings; split from from_proto to keep both short.
std::optional<Error> icp_from_proto(const v1::RegistrationSettings& m, IcpSettings& s) {
  using M = v1::RegistrationSettings;
  if (m.has_method() && !M::Method_IsValid(m.method()))
    return bad("registration.method", m.method(), "POINT_TO_POINT or POINT_TO_PLANE");
  if (m.has_robust_kernel() && !M::RobustKernel_IsValid(m.robust_kernel()))
    return bad("registration.robust_kernel", m.robust_kernel(), "NONE, HUBER or TUKEY");
  if (m.has_method() && m.method() != M::METHOD_UNSPECIFIED)
    s.method =
        m.method() == M::POINT_TO_POINT ? IcpMethod::kPointToPoint : IcpMethod::kPointToPlane;
  if (m.has_robust_kernel() && m.robust_kernel() != M::KERNEL_UNSPECIFIED)
    s.kernel = m.robust_kernel() == M::HUBER   ? RobustKernel::kHuber
               : m.robust_kernel() == M::TUKEY ? RobustKernel::kTukey
                                               : RobustKernel::kNone;
  if (m.has_max_iterations()) s.max_iterations = m.max_iterations();
  if (m.has_max_correspondence_distance_mm())
    s.max_correspondence_distance_mm = m.max_correspondence_distance_mm();
  if (m.has_trimmed_fraction()) s.trimmed_fraction = m.trimmed_fraction();
  if (m.has_kernel_scale_mm()) s.kernel_scale_mm = m.kernel_scale_mm();
  if (m.has_min_error_mm()) s.min_error_mm = m.min_error_mm();
  if (m.has_error_ratio_stop()) s.error_ratio_stop = m.error_ratio_stop();
  // The ranges are the engine's, checked in one place (analysis/registration/icp.hpp).
  return validate(s, "settings: registration.");
}

}  // namespace

Expected<GlobalFitSettings> from_proto(const v1::RegistrationSettings& m) {
  GlobalFitSettings s;
  if (auto error = icp_from_proto(m, s.icp)) return *error;
  if (m.has_pca_initial_alignment()) s.pca_initial_alignment = m.pca_initial_alignment();
  if (m.has_pin_free_directions()) s.boundary.pin_free_directions = m.pin_free_directions();
  for (int i = 0; i < m.symmetry_features_size(); ++i) {
    const v1::SymmetryFeature& f = m.symmetry_features(i);
    const std::string field = "registration.symmetry_features[" + std::to_string(i) + "]";
    const Vec3 center(f.center().x(), f.center().y(), f.center().z());
    if (!center.allFinite())
      return fail(ErrorCode::kInvalidSettings, "settings: " + field + ".center is not finite");
    if (!in_range(f.radius_mm(), 0.001, 1e5))
      return bad(field + ".radius_mm", f.radius_mm(), "0.001 to 1e5");
    s.orientation.symmetry_features.push_back(
        {f.name().empty() ? "feature " + std::to_string(i + 1) : f.name(), center, f.radius_mm()});
  }
  return s;
}

Expected<SpringbackSettings> from_proto(const v1::SpringbackSettings& m) {
  SpringbackSettings s;
  if (m.has_bend_margin_mm()) {
    if (!in_range(m.bend_margin_mm(), 0.0, 1000.0))
      return bad("springback.bend_margin_mm", m.bend_margin_mm(), "0 to 1000");
    s.bend_margin_mm = m.bend_margin_mm();
  }
  if (m.has_max_iterations()) s.local_fit.max_iterations = m.max_iterations();
  if (m.has_max_correspondence_distance_mm()) {
    // The same distance assigns scan points to flanges, so 0 (the engine's "no limit") is
    // refused here; the upper bound is the engine's (validate below).
    if (!(m.max_correspondence_distance_mm() > 0.0))
      return bad("springback.max_correspondence_distance_mm", m.max_correspondence_distance_mm(),
                 "must be > 0: it is also the flange assignment distance");
    s.local_fit.max_correspondence_distance_mm = m.max_correspondence_distance_mm();
    s.assignment_distance_mm = m.max_correspondence_distance_mm();
  }
  if (m.has_station_spacing_mm()) {
    if (!in_range(m.station_spacing_mm(), 1.0, 10000.0))
      return bad("springback.station_spacing_mm", m.station_spacing_mm(), "1 to 10000");
    s.shape.station_spacing_mm = m.station_spacing_mm();
  }
  if (m.has_min_stations()) {
    if (m.min_stations() < 1 || m.min_stations() > 1000)
      return bad("springback.min_stations", m.min_stations(), "1 to 1000");
    s.shape.min_stations = m.min_stations();
  }
  if (m.has_min_curl_sagitta_mm()) {
    if (!in_range(m.min_curl_sagitta_mm(), 0.0, 100.0))
      return bad("springback.min_curl_sagitta_mm", m.min_curl_sagitta_mm(), "0 to 100");
    s.shape.flange.min_curl_sagitta_mm = m.min_curl_sagitta_mm();
  }
  if (auto error = validate(s.local_fit, "settings: springback.")) return *error;
  return s;
}

Expected<int> threads_from_proto(const v1::AnalysisSettings& m) {
  if (!m.has_threads()) return 0;
  if (m.threads() < 0 || m.threads() > 1024) return bad("threads", m.threads(), "0 to 1024");
  return m.threads();
}

void to_proto(const NormalSettings& s, v1::NormalSettings* m) {
  m->set_k_neighbors(s.k_neighbors);
  m->set_radius_mm(s.radius_mm);
}

void to_proto(const ReductionSettings& s, v1::ReductionSettings* m) {
  m->set_kcenter_radius_mm(s.kcenter.radius_mm);
  m->set_kcenter_count(static_cast<std::int32_t>(s.kcenter.center_count));
  m->set_voxel_size_mm(s.voxel_size_mm);
  m->set_min_curvature(s.curvature.min_curvature);
  v1::MeshDecimationSettings& d = *m->mutable_mesh_decimation();
  d.set_enabled(s.mesh_decimation.enabled);
  d.set_target_reduction(s.mesh_decimation.target_reduction);
  d.set_feature_angle_deg(s.mesh_decimation.feature_angle_deg);
  d.set_boundary_vertex_deletion(s.mesh_decimation.boundary_vertex_deletion);
  d.set_max_error_mm(s.mesh_decimation.max_error_mm);
}

void to_proto(const GlobalFitSettings& s, v1::RegistrationSettings* m) {
  using M = v1::RegistrationSettings;
  m->set_method(s.icp.method == IcpMethod::kPointToPoint ? M::POINT_TO_POINT : M::POINT_TO_PLANE);
  m->set_max_iterations(s.icp.max_iterations);
  m->set_max_correspondence_distance_mm(s.icp.max_correspondence_distance_mm);
  m->set_trimmed_fraction(s.icp.trimmed_fraction);
  m->set_robust_kernel(s.icp.kernel == RobustKernel::kHuber   ? M::HUBER
                       : s.icp.kernel == RobustKernel::kTukey ? M::TUKEY
                                                              : M::NONE);
  m->set_kernel_scale_mm(s.icp.kernel_scale_mm);
  m->set_min_error_mm(s.icp.min_error_mm);
  m->set_error_ratio_stop(s.icp.error_ratio_stop);
  m->set_pca_initial_alignment(s.pca_initial_alignment);
  m->set_pin_free_directions(s.boundary.pin_free_directions);
  m->clear_symmetry_features();
  for (const SymmetryFeature& f : s.orientation.symmetry_features) {
    v1::SymmetryFeature* out = m->add_symmetry_features();
    out->set_name(f.name);
    out->mutable_center()->set_x(f.center.x());
    out->mutable_center()->set_y(f.center.y());
    out->mutable_center()->set_z(f.center.z());
    out->set_radius_mm(f.radius_mm);
  }
}

void to_proto(const SpringbackSettings& s, v1::SpringbackSettings* m) {
  m->set_bend_margin_mm(s.bend_margin_mm);
  m->set_max_iterations(s.local_fit.max_iterations);
  m->set_max_correspondence_distance_mm(s.local_fit.max_correspondence_distance_mm);
  m->set_station_spacing_mm(s.shape.station_spacing_mm);
  m->set_min_stations(s.shape.min_stations);
  m->set_min_curl_sagitta_mm(s.shape.flange.min_curl_sagitta_mm);
}

}  // namespace springscan::analysis
