#include "analysis/messages/fit_proto.hpp"

namespace springscan::analysis {

void transform_to_proto(const Transform& T, google::protobuf::RepeatedField<double>* out) {
  out->Clear();
  const Eigen::Matrix4d M = T.matrix();
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) out->Add(M(r, c));
}

void to_proto(const GlobalFitResult& fit, const GlobalFitSettings& settings, v1::GlobalFit* out) {
  transform_to_proto(fit.T_cad_scan, out->mutable_transform());
  out->set_rms_initial(fit.rms_initial_mm);
  out->set_rms_after_pca(fit.rms_after_pca_mm);
  out->set_rms_final(fit.rms_final_mm);
  out->set_iterations(fit.icp.iterations);
  out->clear_error_history();
  for (double e : fit.icp.error_history) out->add_error_history(e);
  out->set_converged(fit.icp.converged);
  out->set_inliers(static_cast<std::int64_t>(fit.icp.inliers));
  out->set_method(settings.icp.method == IcpMethod::kPointToPoint ? "point_to_point"
                                                                  : "point_to_plane");
  out->set_stop_reason(fit.icp.stop_reason);
  out->set_ambiguous(fit.ambiguous);
  out->set_orientation_ambiguity(fit.orientation.ambiguity);
  out->set_orientation_decided_by(fit.orientation.decided_by);
}

void to_proto(const std::vector<FreeDirection>& free, v1::GlobalFit* out) {
  out->clear_free_directions();
  for (const FreeDirection& d : free) {
    v1::FreeDirection* m = out->add_free_directions();
    m->mutable_direction()->set_x(d.direction.x());
    m->mutable_direction()->set_y(d.direction.y());
    m->mutable_direction()->set_z(d.direction.z());
    m->set_pinned(d.pinned);
    m->set_shift_mm(d.shift_mm);
    m->set_model_length_mm(d.model_length_mm);
    m->set_scan_length_mm(d.scan_length_mm);
    m->set_rule(d.rule);
  }
}

void to_proto(const DeviationResult& deviation, double color_scale_mm, v1::Deviation* out) {
  const DeviationStatistics& s = deviation.statistics;
  out->set_min(s.min_mm);
  out->set_max(s.max_mm);
  out->set_mean(s.mean_mm);
  out->set_rms(s.rms_mm);
  out->set_p95(s.p95_mm);
  out->set_points(static_cast<std::int64_t>(s.points));
  out->set_reference(deviation.exact ? "cad_surface" : "model_points");
  out->set_color_scale_mm(color_scale_mm);
}

void to_proto(const ReductionOutcome& reduction, const ReductionSettings& settings,
              std::size_t model_points_in, std::size_t scan_points_in, v1::ReductionReport* out) {
  out->set_model_points_in(static_cast<std::int64_t>(model_points_in));
  out->set_model_points_out(static_cast<std::int64_t>(reduction.model_centers.size()));
  out->set_scan_points_in(static_cast<std::int64_t>(scan_points_in));
  out->set_scan_points_out(static_cast<std::int64_t>(reduction.scan_centers.size()));
  out->set_kcenter_radius_mm(settings.kcenter.center_count > 0 ? 0.0 : settings.kcenter.radius_mm);
  out->set_model_covering_radius_mm(reduction.model_covering_radius_mm);
  out->set_scan_covering_radius_mm(reduction.scan_covering_radius_mm);
}

}  // namespace springscan::analysis
