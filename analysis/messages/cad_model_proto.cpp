#include "analysis/messages/cad_model_proto.hpp"

#include <google/protobuf/io/coded_stream.h>
#include <google/protobuf/io/zero_copy_stream_impl_lite.h>

#include <cmath>

#include "analysis/io/sha256.hpp"

namespace springscan::analysis {
namespace {

void set(v1::Vec3* out, const Vec3& v) {
  out->set_x(v.x());
  out->set_y(v.y());
  out->set_z(v.z());
}

Vec3 get(const v1::Vec3& v) { return {v.x(), v.y(), v.z()}; }

void samples_to_proto(const PointCloud& cloud, v1::PointCloud* out) {
  out->mutable_xyz()->Reserve(static_cast<int>(3 * cloud.size()));
  for (const Vec3& p : cloud.points) out->add_xyz(p.x()), out->add_xyz(p.y()), out->add_xyz(p.z());
  for (const Vec3& n : cloud.normals)
    out->add_normals(n.x()), out->add_normals(n.y()), out->add_normals(n.z());
  for (int id : cloud.face_ids) out->add_face_ids(id);
}

Expected<PointCloud> samples_from_proto(const v1::PointCloud& in) {
  const auto n = static_cast<std::size_t>(in.xyz_size() / 3);
  if (static_cast<std::size_t>(in.xyz_size()) != 3 * n ||
      (in.normals_size() != 0 && in.normals_size() != in.xyz_size()) ||
      (in.face_ids_size() != 0 && static_cast<std::size_t>(in.face_ids_size()) != n))
    return fail(ErrorCode::kCorruption,
                "cached model: samples: inconsistent xyz/normals/face_ids sizes");
  PointCloud cloud;
  cloud.points.reserve(n);
  for (std::size_t i = 0; i < n; ++i)
    cloud.points.emplace_back(in.xyz(static_cast<int>(3 * i)), in.xyz(static_cast<int>(3 * i + 1)),
                              in.xyz(static_cast<int>(3 * i + 2)));
  for (std::size_t i = 0; in.normals_size() > 0 && i < n; ++i)
    cloud.normals.emplace_back(in.normals(static_cast<int>(3 * i)),
                               in.normals(static_cast<int>(3 * i + 1)),
                               in.normals(static_cast<int>(3 * i + 2)));
  cloud.face_ids.assign(in.face_ids().begin(), in.face_ids().end());
  return cloud;
}

}  // namespace

v1::CachedPartModel to_proto(const PartModel& model, const std::string& source_sha256,
                             const std::string& settings_key) {
  v1::CachedPartModel out;
  out.set_format_version(kCachedPartModelVersion);
  out.set_source_sha256(source_sha256);
  out.set_settings_key(settings_key);
  samples_to_proto(model.samples, out.mutable_samples());
  for (const Flange& f : model.segmentation.flanges) {
    auto* m = out.add_flanges();
    m->set_id(f.id);
    for (int id : f.face_ids) m->add_face_ids(id);
    set(m->mutable_point(), f.point);
    set(m->mutable_normal(), f.normal);
    m->set_area_mm2(f.area_mm2);
    m->set_thickness_mm(f.thickness_mm);
  }
  for (const Bend& b : model.segmentation.bends) {
    auto* m = out.add_bends();
    m->set_id(b.id);
    for (int id : b.face_ids) m->add_face_ids(id);
    set(m->mutable_axis_point(), b.axis_point);
    set(m->mutable_axis_direction(), b.axis_direction);
    m->set_radius_mm(b.radius_mm);
    m->set_nominal_angle_deg(b.nominal_angle_deg);
    m->set_flange_a(b.flange_a);
    m->set_flange_b(b.flange_b);
  }
  for (int id : model.segmentation.other_faces) out.add_other_faces(id);
  out.set_face_count(model.face_count);
  return out;
}

Expected<PartModel> from_proto(const v1::CachedPartModel& message) {
  auto samples = samples_from_proto(message.samples());
  if (!samples) return samples.error();
  PartModel model;
  model.samples = std::move(*samples);
  model.face_count = message.face_count();
  const auto valid = [&](int id) { return id >= 0 && id < model.face_count; };
  for (int id : model.samples.face_ids)
    if (!valid(id))
      return fail(ErrorCode::kCorruption,
                  "cached model: sample face id " + std::to_string(id) + " out of range");
  for (const auto& m : message.flanges()) {
    Flange f;
    f.id = m.id();
    f.face_ids.assign(m.face_ids().begin(), m.face_ids().end());
    f.point = get(m.point());
    f.normal = get(m.normal());
    f.area_mm2 = m.area_mm2();
    f.thickness_mm = m.thickness_mm();
    model.segmentation.flanges.push_back(std::move(f));
  }
  for (const auto& m : message.bends()) {
    Bend b;
    b.id = m.id();
    b.face_ids.assign(m.face_ids().begin(), m.face_ids().end());
    b.axis_point = get(m.axis_point());
    b.axis_direction = get(m.axis_direction());
    b.radius_mm = m.radius_mm();
    b.nominal_angle_deg = m.nominal_angle_deg();
    b.flange_a = m.flange_a();
    b.flange_b = m.flange_b();
    model.segmentation.bends.push_back(std::move(b));
  }
  model.segmentation.other_faces.assign(message.other_faces().begin(), message.other_faces().end());
  return model;
}

namespace {

// One optional double of CadModelSettings onto its C++ field, checked against [lo, hi].
std::string apply_range(bool present, double value, double lo, double hi, const char* name,
                        double& target) {
  if (!present) return {};
  if (!(value >= lo && value <= hi))
    return std::string("settings: cad_model.") + name + " = " + std::to_string(value) +
           " (allowed: " + std::to_string(lo) + " to " + std::to_string(hi) + ")";
  target = value;
  return {};
}

}  // namespace

Expected<CadModelSettings> from_proto(const v1::CadModelSettings& message,
                                      CadModelSettings settings) {
  if (message.has_sample_count()) {
    if (message.sample_count() < 100 || message.sample_count() > 10'000'000)
      return fail(ErrorCode::kInvalidSettings,
                  "settings: cad_model.sample_count = " + std::to_string(message.sample_count()) +
                      " (allowed: 100 to 10000000)");
    settings.sampling.sample_count = message.sample_count();
  }
  if (message.has_linear_deflection_mm()) {
    if (!(message.linear_deflection_mm() > 0.0) || !std::isfinite(message.linear_deflection_mm()))
      return fail(ErrorCode::kInvalidSettings, "settings: cad_model.linear_deflection_mm = " +
                                                   std::to_string(message.linear_deflection_mm()) +
                                                   " (must be > 0)");
    settings.import.linear_deflection_mm = message.linear_deflection_mm();
  }
  if (message.has_angular_deflection_deg()) {
    const double value = message.angular_deflection_deg();
    if (!(value > 0.0 && value < 90.0))
      return fail(ErrorCode::kInvalidSettings, "settings: cad_model.angular_deflection_deg = " +
                                                   std::to_string(value) + " (must be in (0, 90))");
    settings.import.angular_deflection_deg = value;
  }
  CadImportSettings& im = settings.import;
  CadSegmentationSettings& sg = settings.segmentation;
  const auto& m = message.segmentation();
  const std::string bad[] = {
      apply_range(message.has_sewing_tolerance_mm(), message.sewing_tolerance_mm(), 1e-6, 10.0,
                  "sewing_tolerance_mm", im.sewing_tolerance_mm),
      apply_range(message.has_min_plausible_size_mm(), message.min_plausible_size_mm(), 0.0, 1000.0,
                  "min_plausible_size_mm", im.min_plausible_size_mm),
      apply_range(m.has_coplanar_angle_deg(), m.coplanar_angle_deg(), 1e-3, 10.0,
                  "segmentation.coplanar_angle_deg", sg.coplanar_angle_deg),
      apply_range(m.has_coplanar_distance_mm(), m.coplanar_distance_mm(), 1e-4, 5.0,
                  "segmentation.coplanar_distance_mm", sg.coplanar_distance_mm),
      apply_range(m.has_coaxial_distance_mm(), m.coaxial_distance_mm(), 1e-4, 5.0,
                  "segmentation.coaxial_distance_mm", sg.coaxial_distance_mm),
      apply_range(m.has_same_radius_mm(), m.same_radius_mm(), 1e-4, 5.0,
                  "segmentation.same_radius_mm", sg.same_radius_mm),
      apply_range(m.has_max_sheet_thickness_mm(), m.max_sheet_thickness_mm(), 0.01, 50.0,
                  "segmentation.max_sheet_thickness_mm", sg.max_sheet_thickness_mm),
  };
  for (const std::string& e : bad)
    if (!e.empty()) return fail(ErrorCode::kInvalidSettings, e);
  if (message.has_sew_loose_faces()) im.sew_loose_faces = message.sew_loose_faces();
  if (message.has_heal()) im.heal = message.heal();
  if (message.has_sample_seed()) settings.sampling.seed = message.sample_seed();
  return settings;
}

v1::CadModelSettings to_proto(const CadModelSettings& s) {
  v1::CadModelSettings m;
  m.set_sample_count(s.sampling.sample_count);
  m.set_sample_seed(s.sampling.seed);
  m.set_linear_deflection_mm(s.import.linear_deflection_mm);
  m.set_angular_deflection_deg(s.import.angular_deflection_deg);
  m.set_sewing_tolerance_mm(s.import.sewing_tolerance_mm);
  m.set_sew_loose_faces(s.import.sew_loose_faces);
  m.set_heal(s.import.heal);
  m.set_min_plausible_size_mm(s.import.min_plausible_size_mm);
  auto* g = m.mutable_segmentation();
  g->set_coplanar_angle_deg(s.segmentation.coplanar_angle_deg);
  g->set_coplanar_distance_mm(s.segmentation.coplanar_distance_mm);
  g->set_coaxial_distance_mm(s.segmentation.coaxial_distance_mm);
  g->set_same_radius_mm(s.segmentation.same_radius_mm);
  g->set_max_sheet_thickness_mm(s.segmentation.max_sheet_thickness_mm);
  return m;
}

std::string model_settings_key(const CadModelSettings& settings) {
  std::string bytes;
  {
    google::protobuf::io::StringOutputStream stream(&bytes);
    google::protobuf::io::CodedOutputStream coded(&stream);
    coded.SetSerializationDeterministic(true);
    to_proto(settings).SerializeToCodedStream(&coded);
  }
  return "model-settings-sha256:" + sha256_hex(bytes);
}

}  // namespace springscan::analysis
