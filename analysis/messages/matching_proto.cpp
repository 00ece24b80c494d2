// Proto conversions of the matching and compensation stages (matching_proto.hpp).
#include "analysis/messages/matching_proto.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>

namespace springscan::analysis {
namespace {

Error bad(const std::string& field, double value, const std::string& rule) {
  return fail(ErrorCode::kInvalidSettings,
              "settings: " + field + " = " + std::to_string(value) + " (" + rule + ")");
}

void set_vec(const Vec3& p, v1::Vec3* out) {
  out->set_x(p.x());
  out->set_y(p.y());
  out->set_z(p.z());
}

void set_correspondence(const DeformationVector& v, bool refined, v1::Correspondence* c) {
  set_vec(v.model, c->mutable_model());
  set_vec(v.scan, c->mutable_scan());
  c->set_model_index(static_cast<std::int32_t>(v.model_index));
  c->set_scan_index(v.scan_index == UINT32_MAX ? -1 : static_cast<std::int32_t>(v.scan_index));
  c->set_squared_distance(v.squared_distance_mm2);
  if (refined) {
    c->set_uncertainty_mm(v.uncertainty_mm);
    c->set_support_points(v.support_points);
  }
}

}  // namespace

Expected<DeformationFieldSettings> from_proto(const v1::DeformationFieldSettings& m) {
  DeformationFieldSettings s;
  if (m.has_method()) {
    switch (m.method()) {
      case v1::DeformationFieldSettings::NEAREST_NEIGHBOR:
        s.method = CorrespondenceMethod::kNearestNeighbor;
        break;
      case v1::DeformationFieldSettings::MIN_COST_MATCHING:
        s.method = CorrespondenceMethod::kMinCostMatching;
        break;
      default:
        break;  // METHOD_UNSPECIFIED keeps the default
    }
  }
  if (m.has_candidate_neighbors()) {
    if (m.candidate_neighbors() < 1 || m.candidate_neighbors() > 1024) {
      return bad("deformation_field.candidate_neighbors", m.candidate_neighbors(), "1 to 1024");
    }
    s.matching.candidate_neighbors = m.candidate_neighbors();
  }
  if (m.has_dense_limit()) {
    if (m.dense_limit() < 0)
      return bad("deformation_field.dense_limit", m.dense_limit(), "must be >= 0");
    s.matching.dense_limit = m.dense_limit();
  }
  if (m.has_refine()) s.refinement.enabled = m.refine();
  if (m.has_support_radius_mm()) {
    if (!(m.support_radius_mm() > 0.0 && m.support_radius_mm() <= 50.0))
      return bad("deformation_field.support_radius_mm", m.support_radius_mm(), "0 to 50");
    s.refinement.support_radius_mm = m.support_radius_mm();
  }
  if (m.has_normal_window_mm()) {
    if (!(m.normal_window_mm() > 0.0 && m.normal_window_mm() <= 50.0))
      return bad("deformation_field.normal_window_mm", m.normal_window_mm(), "0 to 50");
    s.refinement.normal_window_mm = m.normal_window_mm();
  }
  return s;
}

Expected<CompensationSettings> from_proto(const v1::CompensationSettings& m) {
  CompensationSettings s;
  if (m.has_scale()) {
    if (!std::isfinite(m.scale())) return bad("compensation.scale", m.scale(), "must be finite");
    s.scale = m.scale();
  }
  if (m.has_max_magnitude_mm()) {
    if (!(m.max_magnitude_mm() > 0.0) || !std::isfinite(m.max_magnitude_mm())) {
      return bad("compensation.max_magnitude_mm", m.max_magnitude_mm(), "must be > 0");
    }
    s.max_magnitude_mm = m.max_magnitude_mm();
  }
  if (m.has_smoothing_radius_mm()) {
    if (!(m.smoothing_radius_mm() >= 0.0) || !std::isfinite(m.smoothing_radius_mm())) {
      return bad("compensation.smoothing_radius_mm", m.smoothing_radius_mm(),
                 "must be >= 0; 0 = automatic");
    }
    s.smoothing_radius_mm = m.smoothing_radius_mm();
  }
  return s;
}

void to_proto(const DeformationFieldSettings& s, v1::DeformationFieldSettings* m) {
  m->set_method(s.method == CorrespondenceMethod::kNearestNeighbor
                    ? v1::DeformationFieldSettings::NEAREST_NEIGHBOR
                    : v1::DeformationFieldSettings::MIN_COST_MATCHING);
  m->set_candidate_neighbors(s.matching.candidate_neighbors);
  m->set_dense_limit(s.matching.dense_limit);
  m->set_refine(s.refinement.enabled);
  m->set_support_radius_mm(s.refinement.support_radius_mm);
  m->set_normal_window_mm(s.refinement.normal_window_mm);
}

void to_proto(const CompensationSettings& s, v1::CompensationSettings* m) {
  m->set_scale(s.scale);
  m->set_max_magnitude_mm(s.max_magnitude_mm);
  m->set_smoothing_radius_mm(s.smoothing_radius_mm);
}

void to_proto(const DeformationField& field, v1::DeformationField* m) {
  m->Clear();
  m->set_method(to_string(field.method));
  for (const auto& v : field.vectors) set_correspondence(v, field.refined, m->add_vectors());
  for (const auto& v : field.matched) set_correspondence(v, false, m->add_matching());
  if (field.refined) {
    m->set_refinement("flange_motion_surface");
    m->set_scan_coverage(field.scan_coverage);
    m->set_residual_rms_mm(field.residual_rms_mm);
    for (const std::uint32_t i : field.uncovered)
      m->add_uncovered_model_indices(static_cast<std::int32_t>(i));
  }
  m->set_coverage(field.coverage);
  m->set_model_points(static_cast<std::int32_t>(field.model_points));
  m->set_scan_points(static_cast<std::int32_t>(field.scan_points));
  m->set_total_cost(field.total_cost_mm2);
  m->set_optimality_certified(field.optimality_certified);
  m->set_nearest_neighbor_coverage(field.nearest_neighbor_coverage);
}

Expected<DeformationField> from_proto(const v1::DeformationField& m) {
  DeformationField field;
  field.method = m.method() == to_string(CorrespondenceMethod::kNearestNeighbor)
                     ? CorrespondenceMethod::kNearestNeighbor
                     : CorrespondenceMethod::kMinCostMatching;
  field.refined = !m.refinement().empty();
  field.vectors.reserve(static_cast<std::size_t>(m.vectors_size()));
  for (int i = 0; i < m.vectors_size(); ++i) {
    const auto& c = m.vectors(i);
    DeformationVector v;
    v.model = Vec3(c.model().x(), c.model().y(), c.model().z());
    v.scan = Vec3(c.scan().x(), c.scan().y(), c.scan().z());
    if (!v.model.allFinite() || !v.scan.allFinite())
      return fail(ErrorCode::kCorruption,
                  "deformation_field.vectors[" + std::to_string(i) + "] is not finite");
    v.model_index = static_cast<std::uint32_t>(std::max(0, c.model_index()));
    v.squared_distance_mm2 = c.squared_distance();
    v.uncertainty_mm = c.uncertainty_mm();
    v.support_points = c.support_points();
    field.vectors.push_back(v);
  }
  field.model_points = static_cast<std::size_t>(std::max(0, m.model_points()));
  field.scan_points = static_cast<std::size_t>(std::max(0, m.scan_points()));
  field.coverage = m.coverage();
  field.scan_coverage = m.scan_coverage();
  field.residual_rms_mm = m.residual_rms_mm();
  return field;
}

void append_to_report(const Compensation& compensation, v1::InspectionReport* report) {
  for (const auto& v : compensation.vectors) {
    if (!v.supported) continue;
    auto* c = report->add_compensation();
    set_vec(v.point, c->mutable_point());
    set_vec(v.vector, c->mutable_vector());
  }
}

}  // namespace springscan::analysis
