#include "simulators/parts/produced_part.hpp"

#include <algorithm>
#include <cmath>
#include <deque>
#include <limits>
#include <numbers>
#include <string>
#include <utility>

#include "analysis/cad/segmentation.hpp"
#include "analysis/core/kdtree.hpp"
#include "analysis/core/parallel.hpp"

namespace springscan::parts {

// One bend as the walk placed it, in the CAD frame of its parent flange.
struct BendFrame {
  Vec3 c = Vec3::Zero();        // on the CAD axis
  Vec3 d = Vec3::UnitX();       // axis, oriented so that e0 turns into e1 by +span
  Vec3 e0 = Vec3::UnitY();      // from the axis towards the parent flange's sheet (phi = 0)
  Vec3 e0_perp = Vec3::Zero();  // d x e0 (phi = 90 degrees)
  double span_rad = 0.0;        // Phi: the angle the sheet turns in the CAD part
  double springback_rad = 0.0;  // applied (0 for hems and closing bends)
  double r_in = 0.0, r_out = 0.0, axial_min = 0.0, axial_max = 0.0;
  Transform T_parent = Transform::Identity();
};

enum class FaceKind { kFlange, kBend, kOther };

struct ProducedPartData {
  std::vector<FaceKind> face_kind;
  std::vector<int> face_index;  // Flange::id or Bend::id of the face, -1 for other faces
  std::vector<BendFrame> frames;
  std::vector<Transform> flange_T;
  std::vector<std::vector<int>> flange_bends;              // bends touching each flange
  std::vector<std::vector<int>> face_candidates;           // other faces: regions they touch
  std::vector<int> sample_region;                          // per KD-tree point: region code
  std::vector<std::vector<std::uint32_t>> region_samples;  // KD-tree points of each region
  std::unique_ptr<KdTree> tree;                            // flange and bend samples
  int flange_count = 0;
  double wedge_tolerance_mm = 0.05;
};

namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

Transform rotation_about(const Vec3& c, const Vec3& d, double angle_rad) {
  Transform T = Transform::Identity();
  T.linear() = Eigen::AngleAxisd(angle_rad, d).toRotationMatrix();
  T.translation() = c - T.linear() * c;
  return T;
}

// From the axis towards the sheet of `flange` (its mid-plane), perpendicular to the axis: the
// material as seen from the axis, which decides the sense of the bend whatever the normals say.
Vec3 towards_sheet(const Flange& flange, const Vec3& c, const Vec3& d) {
  const Vec3 mid = flange.point - 0.5 * flange.thickness_mm * flange.normal;
  Vec3 e = flange.normal * ((mid - c).dot(flange.normal) >= 0.0 ? 1.0 : -1.0);
  e -= e.dot(d) * d;
  return e.normalized();
}

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

// Fills face_kind/face_index, flange_bends and the bends' axial extents and radii.
void classify_faces(const PartModel& model, const CadShape& shape, ProducedPartData& data) {
  const auto& seg = model.segmentation;
  const auto faces = static_cast<std::size_t>(shape.face_count());
  data.face_kind.assign(faces, FaceKind::kOther);
  data.face_index.assign(faces, -1);
  data.flange_count = static_cast<int>(seg.flanges.size());
  data.flange_bends.assign(seg.flanges.size(), {});
  for (std::size_t i = 0; i < seg.flanges.size(); ++i) {
    for (int f : seg.flanges[i].face_ids) {
      data.face_kind[static_cast<std::size_t>(f)] = FaceKind::kFlange;
      data.face_index[static_cast<std::size_t>(f)] = static_cast<int>(i);
    }
  }
  for (std::size_t i = 0; i < seg.bends.size(); ++i) {
    for (int f : seg.bends[i].face_ids) {
      data.face_kind[static_cast<std::size_t>(f)] = FaceKind::kBend;
      data.face_index[static_cast<std::size_t>(f)] = static_cast<int>(i);
    }
    data.flange_bends[static_cast<std::size_t>(seg.bends[i].flange_a)].push_back(
        static_cast<int>(i));
    data.flange_bends[static_cast<std::size_t>(seg.bends[i].flange_b)].push_back(
        static_cast<int>(i));
  }
}

// The bend's frame with `parent` on the root side (everything but T_parent and springback).
BendFrame bend_frame(const PartModel& model, const CadMesh& mesh, const ProducedPartData& data,
                     int bend_id, int parent) {
  const auto& seg = model.segmentation;
  const Bend& bend = seg.bends[static_cast<std::size_t>(bend_id)];
  const int child = bend.flange_a == parent ? bend.flange_b : bend.flange_a;
  const Flange& fp = seg.flanges[static_cast<std::size_t>(parent)];
  const Flange& fc = seg.flanges[static_cast<std::size_t>(child)];
  BendFrame f;
  f.c = bend.axis_point;
  const Vec3 axis = bend.axis_direction.normalized();
  f.e0 = towards_sheet(fp, f.c, axis);
  const Vec3 e1 = towards_sheet(fc, f.c, axis);
  const double turn = f.e0.cross(e1).dot(axis);
  f.d = turn >= 0.0 ? axis : Vec3(-axis);
  f.e0_perp = f.d.cross(f.e0);
  f.span_rad = std::atan2(std::abs(turn), f.e0.dot(e1));
  f.r_in = bend.radius_mm;
  f.r_out = bend.radius_mm + std::max(fp.thickness_mm, fc.thickness_mm);
  f.axial_min = std::numeric_limits<double>::infinity();
  f.axial_max = -f.axial_min;
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    const auto face = static_cast<std::size_t>(mesh.triangle_faces[t]);
    if (data.face_kind[face] != FaceKind::kBend || data.face_index[face] != bend_id) continue;
    for (auto v : mesh.triangles[t]) {
      const double s = (mesh.vertices[v] - f.c).dot(f.d);
      f.axial_min = std::min(f.axial_min, s);
      f.axial_max = std::max(f.axial_max, s);
    }
  }
  return f;
}

// An unplaced flange that touches a placed one through other faces: {unplaced, placed}.
std::pair<int, int> rigid_attachment(const std::vector<CadFaceInfo>& faces,
                                     const ProducedPartData& data, const std::vector<bool>& placed,
                                     const PartModel& model) {
  for (std::size_t u = 0; u < placed.size(); ++u) {
    if (placed[u]) continue;
    std::vector<int> frontier = model.segmentation.flanges[u].face_ids, seen = frontier;
    for (int level = 0; level < 4 && !frontier.empty(); ++level) {
      std::vector<int> next;
      for (int f : frontier) {
        for (int n : faces[static_cast<std::size_t>(f)].neighbors) {
          if (std::find(seen.begin(), seen.end(), n) != seen.end()) continue;
          seen.push_back(n);
          const auto k = data.face_kind[static_cast<std::size_t>(n)];
          const int index = data.face_index[static_cast<std::size_t>(n)];
          if (k == FaceKind::kFlange && placed[static_cast<std::size_t>(index)]) {
            return {static_cast<int>(u), index};
          }
          if (k == FaceKind::kOther) next.push_back(n);
        }
      }
      frontier = std::move(next);
    }
  }
  return {-1, -1};
}

// The breadth-first walk from the root: flange transforms, bend frames and truths.
void walk(const PartModel& model, const CadShape& shape, const std::vector<CadFaceInfo>& faces,
          const std::vector<double>& springback_deg, const ProducedPartSettings& settings,
          ProducedPartData& data, ProducedPart& part) {
  const auto& seg = model.segmentation;
  const std::size_t nf = seg.flanges.size(), nb = seg.bends.size();
  std::vector<bool> placed(nf, false), done(nb, false);
  data.flange_T.assign(nf, Transform::Identity());
  data.frames.assign(nb, BendFrame{});
  part.bends.assign(nb, BendTruth{});
  std::deque<int> queue{part.report.root_flange};
  placed[static_cast<std::size_t>(part.report.root_flange)] = true;
  while (true) {
    while (!queue.empty()) {
      const int p = queue.front();
      queue.pop_front();
      for (int b : data.flange_bends[static_cast<std::size_t>(p)]) {
        if (done[static_cast<std::size_t>(b)]) continue;
        done[static_cast<std::size_t>(b)] = true;
        const Bend& bend = seg.bends[static_cast<std::size_t>(b)];
        const int child = bend.flange_a == p ? bend.flange_b : bend.flange_a;
        BendFrame f = bend_frame(model, shape.mesh(), data, b, p);
        f.T_parent = data.flange_T[static_cast<std::size_t>(p)];
        BendTruth& truth = part.bends[static_cast<std::size_t>(b)];
        truth.bend_id = b;
        truth.parent_flange = p;
        truth.child_flange = child;
        truth.radius_mm = bend.radius_mm;
        truth.nominal_angle_deg = bend.nominal_angle_deg;
        truth.requested_springback_deg = springback_deg[static_cast<std::size_t>(b)];
        truth.hem = bend.nominal_angle_deg >= settings.hem_angle_deg;
        truth.closes_cycle = placed[static_cast<std::size_t>(child)];
        truth.springback_deg =
            truth.hem || truth.closes_cycle ? 0.0 : truth.requested_springback_deg;
        f.springback_rad = truth.springback_deg * kDeg;
        truth.axis_point = f.T_parent * f.c;
        truth.axis_direction = f.T_parent.linear() * f.d;
        truth.produced_angle_deg = bend.nominal_angle_deg - truth.springback_deg;
        if (truth.hem) {
          part.report.hems.push_back(b);
          part.report.warnings.push_back("bend " + std::to_string(b) +
                                         ": closed hem, springback forced to 0");
        }
        if (truth.closes_cycle) {
          // The flanges were placed through other bends: measure what this bend came out as.
          const Vec3 e1 = towards_sheet(seg.flanges[static_cast<std::size_t>(child)], f.c, f.d);
          const Vec3 a = f.T_parent.linear() * f.e0;
          const Vec3 b1 = data.flange_T[static_cast<std::size_t>(child)].linear() * e1;
          truth.produced_angle_deg = std::acos(std::clamp(a.dot(b1), -1.0, 1.0)) / kDeg;
          truth.cycle_error_deg =
              truth.produced_angle_deg - (bend.nominal_angle_deg - truth.requested_springback_deg);
          part.report.closing_bends.push_back(b);
          part.report.warnings.push_back("bend " + std::to_string(b) + " closes a cycle: off by " +
                                         std::to_string(truth.cycle_error_deg) + " deg");
        } else {
          data.flange_T[static_cast<std::size_t>(child)] =
              f.T_parent * rotation_about(f.c, f.d, -f.springback_rad);
          placed[static_cast<std::size_t>(child)] = true;
          queue.push_back(child);
        }
        if (std::abs(f.span_rad / kDeg - bend.nominal_angle_deg) > 0.01 && !truth.hem) {
          part.report.warnings.push_back("bend " + std::to_string(b) + ": flanges turn " +
                                         std::to_string(f.span_rad / kDeg) + " deg, nominal " +
                                         std::to_string(bend.nominal_angle_deg));
        }
        data.frames[static_cast<std::size_t>(b)] = f;
      }
    }
    const auto [u, with] = rigid_attachment(faces, data, placed, model);
    if (u < 0) break;
    data.flange_T[static_cast<std::size_t>(u)] = data.flange_T[static_cast<std::size_t>(with)];
    placed[static_cast<std::size_t>(u)] = true;
    part.report.rigid_flanges.push_back(u);
    part.report.warnings.push_back("flange " + std::to_string(u) +
                                   " is joined by no bend: moves with flange " +
                                   std::to_string(with));
    queue.push_back(u);
  }
  for (std::size_t u = 0; u < nf; ++u) {
    if (placed[u]) continue;
    part.report.rigid_flanges.push_back(static_cast<int>(u));
    part.report.warnings.push_back("flange " + std::to_string(u) +
                                   " is attached to nothing: not moved");
  }
}

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
  classify_faces(model, shape, *data);
  walk(model, shape, faces, springback_deg, settings, *data, part);
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
