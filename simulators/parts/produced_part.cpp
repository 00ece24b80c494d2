#include "simulators/parts/produced_part.hpp"

#include <algorithm>
#include <cmath>
#include <deque>
#include <limits>
#include <numbers>
#include <string>
#include <utility>

#include "analysis/cad/sampling.hpp"
#include "analysis/cad/segmentation.hpp"
#include "analysis/core/kdtree.hpp"
#include "analysis/core/parallel.hpp"
#include "simulators/parts/produced_part_internal.hpp"

namespace springscan::parts {
namespace {

using detail::rotation_about;

// Angular position of p about the bend, clamped into [0, span] (to the nearer end).
double clamped_phi(const BendFrame& f, const Vec3& p) {
  const Vec3 v = p - f.c;
  const double phi = std::atan2(v.dot(f.e0_perp), v.dot(f.e0));
  const double two_pi = 2.0 * std::numbers::pi;
  if (phi > f.span_rad) return (phi - f.span_rad < two_pi - phi) ? f.span_rad : 0.0;
  if (phi < 0.0) return (-phi < phi + two_pi - f.span_rad) ? 0.0 : f.span_rad;
  return phi;
}

bool in_wedge(const BendFrame& f, const Vec3& p, double tol) {
  const Vec3 v = p - f.c;
  const double s = v.dot(f.d);
  if (s < f.axial_min - tol || s > f.axial_max + tol) return false;
  const double rho = (v - s * f.d).norm();
  if (rho < f.r_in - tol || rho > f.r_out + tol) return false;
  const double phi = std::atan2(v.dot(f.e0_perp), v.dot(f.e0));
  return phi >= 0.0 && phi <= f.span_rad;
}

Transform bend_zone_transform(const BendFrame& f, const Vec3& p) {
  if (f.springback_rad == 0.0 || f.span_rad <= 0.0) return f.T_parent;
  const double phi = clamped_phi(f, p);
  return f.T_parent * rotation_about(f.c, f.d, -f.springback_rad * phi / f.span_rad);
}

// The regions (flange id, or flange_count + bend id) an other face touches, through chains of
// at most `depth` other faces.
std::vector<int> touching_regions(int face, const std::vector<CadFaceInfo>& faces,
                                  const ProducedPartData& data, int depth) {
  std::vector<int> regions, seen{face};
  std::vector<int> frontier{face};
  for (int level = 0; level <= depth && !frontier.empty(); ++level) {
    std::vector<int> next;
    for (int f : frontier) {
      for (int n : faces[static_cast<std::size_t>(f)].neighbors) {
        if (std::find(seen.begin(), seen.end(), n) != seen.end()) continue;
        seen.push_back(n);
        const auto k = data.face_kind[static_cast<std::size_t>(n)];
        const int index = data.face_index[static_cast<std::size_t>(n)];
        if (k == FaceKind::kFlange) regions.push_back(index);
        if (k == FaceKind::kBend) regions.push_back(data.flange_count + index);
        if (k == FaceKind::kOther) next.push_back(n);
      }
    }
    if (!regions.empty()) break;  // the nearest ring of regions is the one the face touches
    frontier = std::move(next);
  }
  std::sort(regions.begin(), regions.end());
  regions.erase(std::unique(regions.begin(), regions.end()), regions.end());
  return regions;
}

// The region a point of an other face belongs to: its nearest flange or bend sample among the
// regions the face touches (searched one by one when none of the 32 nearest is one of them).
int region_of(const ProducedPartData& data, const Vec3& p, int face) {
  constexpr std::size_t kK = 32;
  std::uint32_t idx[kK];
  double d2[kK];
  const std::size_t n = data.tree->knn(p, kK, idx, d2);
  const auto& candidates = data.face_candidates[static_cast<std::size_t>(face)];
  for (std::size_t i = 0; i < n; ++i) {
    const int r = data.sample_region[idx[i]];
    if (candidates.empty() || std::binary_search(candidates.begin(), candidates.end(), r)) {
      return r;
    }
  }
  if (candidates.size() == 1) return candidates.front();
  int best = n > 0 ? data.sample_region[idx[0]] : 0;
  double best_d2 = std::numeric_limits<double>::infinity();
  for (int r : candidates) {
    for (std::uint32_t i : data.region_samples[static_cast<std::size_t>(r)]) {
      const double d = (data.tree->points()[i] - p).squaredNorm();
      if (d < best_d2) best_d2 = d, best = r;
    }
  }
  return best;
}

}  // namespace

Transform ProducedPart::local_transform(const Vec3& p, int face) const {
  const auto& d = *data;
  if (face < 0 || static_cast<std::size_t>(face) >= d.face_kind.size()) {
    return Transform::Identity();
  }
  const auto f = static_cast<std::size_t>(face);
  if (d.face_kind[f] == FaceKind::kFlange)
    return d.flange_T[static_cast<std::size_t>(d.face_index[f])];
  if (d.face_kind[f] == FaceKind::kBend) {
    return bend_zone_transform(d.frames[static_cast<std::size_t>(d.face_index[f])], p);
  }
  if (!d.tree || d.tree->empty()) return Transform::Identity();
  const int region = region_of(d, p, face);
  if (region >= d.flange_count) {
    return bend_zone_transform(d.frames[static_cast<std::size_t>(region - d.flange_count)], p);
  }
  for (int b : d.flange_bends[static_cast<std::size_t>(region)]) {
    const BendFrame& frame = d.frames[static_cast<std::size_t>(b)];
    if (in_wedge(frame, p, d.wedge_tolerance_mm)) return bend_zone_transform(frame, p);
  }
  return d.flange_T[static_cast<std::size_t>(region)];
}

namespace {

// The KD-tree of flange and bend samples and the regions every other face touches.
void index_regions(const PartModel& model, const std::vector<CadFaceInfo>& faces,
                   ProducedPartData& data) {
  std::vector<Vec3> points;
  const auto& s = model.samples;
  for (std::size_t i = 0; i < s.size(); ++i) {
    const auto f = static_cast<std::size_t>(s.face_ids[i]);
    if (f >= data.face_kind.size() || data.face_kind[f] == FaceKind::kOther) continue;
    points.push_back(s.points[i]);
    data.sample_region.push_back(data.face_kind[f] == FaceKind::kFlange
                                     ? data.face_index[f]
                                     : data.flange_count + data.face_index[f]);
  }
  data.region_samples.assign(
      static_cast<std::size_t>(data.flange_count) + model.segmentation.bends.size(), {});
  for (std::size_t i = 0; i < data.sample_region.size(); ++i) {
    data.region_samples[static_cast<std::size_t>(data.sample_region[i])].push_back(
        static_cast<std::uint32_t>(i));
  }
  data.tree = std::make_unique<KdTree>(std::move(points));
  data.face_candidates.assign(faces.size(), {});
  for (std::size_t f = 0; f < faces.size(); ++f) {
    if (data.face_kind[f] == FaceKind::kOther) {
      data.face_candidates[f] = touching_regions(static_cast<int>(f), faces, data, 3);
    }
  }
}

}  // namespace

Expected<CadPart> load_cad_part(const std::string& path, const CadModelSettings& settings) {
  auto shape = load_cad(path, settings.import);
  if (!shape) return shape.error();
  CadPart part;
  part.shape = *shape;
  auto samples = sample_cad(part.shape, settings.sampling);
  if (!samples) return samples.error();
  part.model.samples = std::move(*samples);
  part.model.segmentation = segment_cad(part.shape, settings.segmentation);
  part.model.face_count = part.shape.face_count();
  part.model.mesh = tessellation(part.shape);
  return part;
}

Expected<ProducedPart> make_produced_part(const PartModel& model, const CadShape& shape,
                                          const std::vector<double>& springback_deg,
                                          const ProducedPartSettings& settings) {
  const auto& seg = model.segmentation;
  if (shape.empty() || shape.face_count() != model.face_count) {
    return fail("produced part: the shape's face count differs from the model's");
  }
  if (springback_deg.size() != seg.bends.size()) {
    return fail("produced part: " + std::to_string(springback_deg.size()) +
                " springback values for " + std::to_string(seg.bends.size()) + " bends");
  }
  if (seg.flanges.empty()) return fail("produced part: the model has no flange");
  if (!model.samples.has_face_ids()) return fail("produced part: the samples have no face ids");
  ProducedPart part;
  part.report.root_flange = settings.root_flange;
  if (settings.root_flange < 0) {
    const auto largest =
        std::max_element(seg.flanges.begin(), seg.flanges.end(),
                         [](const Flange& a, const Flange& b) { return a.area_mm2 < b.area_mm2; });
    part.report.root_flange = static_cast<int>(largest - seg.flanges.begin());
  } else if (static_cast<std::size_t>(settings.root_flange) >= seg.flanges.size()) {
    return fail("produced part: root_flange " + std::to_string(settings.root_flange) +
                " is not a flange");
  }
  auto data = std::make_shared<ProducedPartData>();
  data->wedge_tolerance_mm = settings.wedge_tolerance_mm;
  const auto faces = describe_faces(shape);
  detail::classify_faces(model, shape, *data);
  detail::walk(model, shape, faces, springback_deg, settings, *data, part);
  index_regions(model, faces, *data);
  part.flange_transforms = data->flange_T;
  part.data = data;

  // The samples and the tessellation, produced.
  part.samples = model.samples;
  parallel_blocks(part.samples.size(), 0, [&](std::size_t, std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      const Transform T = part.local_transform(model.samples.points[i], model.samples.face_ids[i]);
      part.samples.points[i] = T * model.samples.points[i];
      if (part.samples.has_normals())
        part.samples.normals[i] = T.linear() * model.samples.normals[i];
    }
  });
  const CadMesh& cad = shape.mesh();
  part.mesh = cad;
  part.cad_mesh = cad;
  part.faces = faces;
  part.solid = shape.report().solids > 0;
  std::vector<std::int32_t> vertex_face(cad.vertices.size(), -1);
  for (std::size_t t = 0; t < cad.triangles.size(); ++t) {
    for (auto v : cad.triangles[t]) vertex_face[v] = cad.triangle_faces[t];
  }
  parallel_blocks(cad.vertices.size(), 0, [&](std::size_t, std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      part.mesh.vertices[i] = part.produced(cad.vertices[i], vertex_face[i]);
    }
  });
  return part;
}

}  // namespace springscan::parts
