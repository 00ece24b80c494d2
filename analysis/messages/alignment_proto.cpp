// The datum alignment <-> proto (alignment_proto.hpp).
#include "analysis/messages/alignment_proto.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "analysis/messages/fit_proto.hpp"

namespace springscan::analysis {
namespace {

Vec3 from(const v1::Vec3& v) { return {v.x(), v.y(), v.z()}; }

void put(const Vec3& v, v1::Vec3* out) {
  out->set_x(v.x());
  out->set_y(v.y());
  out->set_z(v.z());
}

Expected<DatumKind> kind_from_proto(const v1::Datum& m) {
  switch (m.kind()) {
    case v1::Datum::PAD:
      return DatumKind::kPad;
    case v1::Datum::HOLE:
      return DatumKind::kHole;
    case v1::Datum::SLOT:
      return DatumKind::kSlot;
    case v1::Datum::EDGE:
      return DatumKind::kEdge;
    default:
      return fail(ErrorCode::kInvalidSettings, "settings: alignment.datums '" + m.name() +
                                                   "': kind must be PAD, HOLE, SLOT or EDGE");
  }
}

v1::Datum::Kind kind_to_proto(DatumKind kind) {
  switch (kind) {
    case DatumKind::kPad:
      return v1::Datum::PAD;
    case DatumKind::kHole:
      return v1::Datum::HOLE;
    case DatumKind::kSlot:
      return v1::Datum::SLOT;
    case DatumKind::kEdge:
      return v1::Datum::EDGE;
  }
  return v1::Datum::KIND_UNSPECIFIED;
}

// A config writes the CAD's numbers: unit vectors to a few digits.
Vec3 unit_or_zero(const Vec3& v) { return v.norm() > 0.0 ? Vec3(v.normalized()) : Vec3::Zero(); }

Expected<Datum> datum_from_proto(const v1::Datum& m) {
  auto kind = kind_from_proto(m);
  if (!kind) return kind.error();
  Datum d;
  d.name = m.name();
  d.kind = *kind;
  d.point = from(m.point());
  d.normal = unit_or_zero(from(m.normal()));
  // Only the part across the normal counts: a direction written to a few digits keeps its aim.
  const Vec3 dir = from(m.direction());
  d.direction = unit_or_zero(dir - dir.dot(d.normal) * d.normal);
  if (m.has_radius_mm()) d.radius_mm = m.radius_mm();
  if (m.has_diameter_mm()) d.diameter_mm = m.diameter_mm();
  if (m.has_length_mm()) d.length_mm = m.length_mm();
  if (m.has_thickness_mm()) d.thickness_mm = m.thickness_mm();
  if (m.has_weight()) d.weight = m.weight();
  return d;
}

}  // namespace

Expected<DatumAlignmentSettings> from_proto(const v1::AlignmentSettings& m) {
  DatumAlignmentSettings s;
  for (const v1::Datum& dm : m.datums()) {
    auto d = datum_from_proto(dm);
    if (!d) return d.error();
    s.datums.push_back(std::move(*d));
  }
  if (m.has_search_mm()) s.search_mm = m.search_mm();
  if (m.has_capture_mm()) s.capture_mm = m.capture_mm();
  if (m.has_band_mm()) s.band_mm = m.band_mm();
  if (m.has_min_points()) s.min_points = static_cast<std::size_t>(std::max(m.min_points(), 0));
  if (auto e = validate(s, "settings: alignment: ")) return *e;
  return s;
}

void to_proto(const DatumAlignmentSettings& s, v1::AlignmentSettings* m) {
  m->clear_datums();
  for (const Datum& d : s.datums) {
    v1::Datum& dm = *m->add_datums();
    dm.set_name(d.name);
    dm.set_kind(kind_to_proto(d.kind));
    put(d.point, dm.mutable_point());
    put(d.normal, dm.mutable_normal());
    put(d.direction, dm.mutable_direction());
    dm.set_radius_mm(d.radius_mm);
    dm.set_diameter_mm(d.diameter_mm);
    dm.set_length_mm(d.length_mm);
    dm.set_thickness_mm(d.thickness_mm);
    dm.set_weight(d.weight);
  }
  m->set_search_mm(s.search_mm);
  m->set_capture_mm(s.capture_mm);
  m->set_band_mm(s.band_mm);
  m->set_min_points(static_cast<int>(s.min_points));
}

void alignment_to_proto(const Transform& T_cad_scan_best, const DatumAlignmentResult* datum,
                        v1::Alignment* out) {
  out->Clear();
  out->set_achieved(true);
  if (datum && !datum->achieved) {
    // The datum frame could not be made: the best fit's, the datum named and why.
    out->set_method("best_fit");
    transform_to_proto(T_cad_scan_best, out->mutable_transform());
    out->set_achieved(false);
    out->set_failure(datum->failure);
    out->set_failed_datum(datum->failed_datum);
    return;
  }
  if (!datum) {
    out->set_method("best_fit");
    transform_to_proto(T_cad_scan_best, out->mutable_transform());
    return;
  }
  out->set_method("datum");
  transform_to_proto(datum->T_cad_scan, out->mutable_transform());
  transform_to_proto(datum->T_datum_best, out->mutable_datum_from_best_fit());
  out->set_rotation_from_best_fit_deg(Eigen::AngleAxisd(datum->T_datum_best.linear()).angle() *
                                      180.0 / std::numbers::pi);
  double shift = 0.0;
  for (const DatumResult& r : datum->datums)
    shift = std::max(shift, (datum->T_datum_best * r.datum.point - r.datum.point).norm());
  out->set_shift_from_best_fit_mm(shift);
  out->set_passes(datum->passes);
  for (const DatumRound& r : datum->rounds) {
    v1::AlignmentRound& m = *out->add_rounds();
    m.set_stage(r.stage);
    m.set_band_mm(r.band_mm);
    m.set_moved_mm(r.moved_mm);
    m.set_moved_deg(r.moved_deg);
  }
  for (const DatumResult& r : datum->datums) {
    v1::AlignmentDatum& d = *out->add_datums();
    d.set_name(r.datum.name);
    d.set_kind(to_string(r.datum.kind));
    put(r.datum.point, d.mutable_nominal());
    put(r.measured, d.mutable_measured());
    put(r.residual, d.mutable_residual());
    d.set_residual_mm(r.residual.norm());
    put(r.best_fit_residual, d.mutable_best_fit_residual());
    d.set_best_fit_residual_mm(r.best_fit_residual.norm());
    d.set_constraints(r.constraints);
    d.set_weight(r.datum.weight);
    d.set_points(static_cast<std::int64_t>(r.points));
    d.set_fit_rms_mm(r.fit_rms_mm);
    if (r.datum.kind == DatumKind::kHole || r.datum.kind == DatumKind::kSlot)
      d.set_measured_diameter_mm(r.measured_diameter_mm);
    if (r.datum.kind == DatumKind::kPad) put(r.measured_normal, d.mutable_measured_normal());
    d.set_measured_by(r.measured_by);
  }
}

}  // namespace springscan::analysis
