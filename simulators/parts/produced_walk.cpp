// The walk over the flange-bend graph (produced_part.hpp): which flange is whose parent, the
// frame of every bend and the rigid motion of every flange.
#include <algorithm>
#include <cmath>
#include <deque>
#include <limits>
#include <numbers>
#include <string>
#include <utility>

#include "simulators/parts/produced_part_internal.hpp"

namespace springscan::parts::detail {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;
}  // namespace

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

namespace {

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

struct WalkState {
  const PartModel& model;
  const CadShape& shape;
  const std::vector<double>& springback_deg;
  const ProducedPartSettings& settings;
  ProducedPartData& data;
  ProducedPart& part;
  std::vector<bool> placed;
};

// Bend `b` reached from its flange `p`: its frame and truth, and the child's motion unless the
// child is already placed (the bend closes a cycle). Returns the child to visit next, or -1.
int place_bend(WalkState& w, int b, int p) {
  const auto& seg = w.model.segmentation;
  const Bend& bend = seg.bends[static_cast<std::size_t>(b)];
  const int child = bend.flange_a == p ? bend.flange_b : bend.flange_a;
  BendFrame f = bend_frame(w.model, w.shape.mesh(), w.data, b, p);
  f.T_parent = w.data.flange_T[static_cast<std::size_t>(p)];
  BendTruth& truth = w.part.bends[static_cast<std::size_t>(b)];
  auto& report = w.part.report;
  truth.bend_id = b;
  truth.parent_flange = p;
  truth.child_flange = child;
  truth.radius_mm = bend.radius_mm;
  truth.nominal_angle_deg = bend.nominal_angle_deg;
  truth.requested_springback_deg = w.springback_deg[static_cast<std::size_t>(b)];
  truth.hem = bend.nominal_angle_deg >= w.settings.hem_angle_deg;
  truth.closes_cycle = w.placed[static_cast<std::size_t>(child)];
  truth.springback_deg = truth.hem || truth.closes_cycle ? 0.0 : truth.requested_springback_deg;
  f.springback_rad = truth.springback_deg * kDeg;
  truth.axis_point = f.T_parent * f.c;
  truth.axis_direction = f.T_parent.linear() * f.d;
  truth.produced_angle_deg = bend.nominal_angle_deg - truth.springback_deg;
  const std::string name = "bend " + std::to_string(b);
  if (truth.hem) {
    report.hems.push_back(b);
    report.warnings.push_back(name + ": closed hem, springback forced to 0");
  }
  if (!truth.hem && std::abs(f.span_rad / kDeg - bend.nominal_angle_deg) > 0.01) {
    report.warnings.push_back(name + ": flanges turn " + std::to_string(f.span_rad / kDeg) +
                              " deg, nominal " + std::to_string(bend.nominal_angle_deg));
  }
  w.data.frames[static_cast<std::size_t>(b)] = f;
  if (truth.closes_cycle) {
    // The flanges were placed through other bends: measure what this bend came out as.
    const Vec3 e1 = towards_sheet(seg.flanges[static_cast<std::size_t>(child)], f.c, f.d);
    const Vec3 a = f.T_parent.linear() * f.e0;
    const Vec3 c = w.data.flange_T[static_cast<std::size_t>(child)].linear() * e1;
    truth.produced_angle_deg = std::acos(std::clamp(a.dot(c), -1.0, 1.0)) / kDeg;
    truth.cycle_error_deg =
        truth.produced_angle_deg - (bend.nominal_angle_deg - truth.requested_springback_deg);
    report.closing_bends.push_back(b);
    report.warnings.push_back(name + " closes a cycle: off by " +
                              std::to_string(truth.cycle_error_deg) + " deg");
    return -1;
  }
  w.data.flange_T[static_cast<std::size_t>(child)] =
      f.T_parent * rotation_about(f.c, f.d, -f.springback_rad);
  w.placed[static_cast<std::size_t>(child)] = true;
  return child;
}

}  // namespace

void walk(const PartModel& model, const CadShape& shape, const std::vector<CadFaceInfo>& faces,
          const std::vector<double>& springback_deg, const ProducedPartSettings& settings,
          ProducedPartData& data, ProducedPart& part) {
  const auto& seg = model.segmentation;
  const std::size_t nf = seg.flanges.size(), nb = seg.bends.size();
  WalkState w{model, shape, springback_deg, settings, data, part, std::vector<bool>(nf, false)};
  std::vector<bool> done(nb, false);
  data.flange_T.assign(nf, Transform::Identity());
  data.frames.assign(nb, BendFrame{});
  part.bends.assign(nb, BendTruth{});
  std::deque<int> queue{part.report.root_flange};
  w.placed[static_cast<std::size_t>(part.report.root_flange)] = true;
  while (true) {
    // Breadth first over the bends, in bend id order at each flange.
    while (!queue.empty()) {
      const int p = queue.front();
      queue.pop_front();
      for (int b : data.flange_bends[static_cast<std::size_t>(p)]) {
        if (done[static_cast<std::size_t>(b)]) continue;
        done[static_cast<std::size_t>(b)] = true;
        const int child = place_bend(w, b, p);
        if (child >= 0) queue.push_back(child);
      }
    }
    // A flange no bend reaches moves with a placed flange it touches through other faces.
    const auto [u, with] = rigid_attachment(faces, data, w.placed, model);
    if (u < 0) break;
    data.flange_T[static_cast<std::size_t>(u)] = data.flange_T[static_cast<std::size_t>(with)];
    w.placed[static_cast<std::size_t>(u)] = true;
    part.report.rigid_flanges.push_back(u);
    part.report.warnings.push_back("flange " + std::to_string(u) +
                                   " is joined by no bend: moves with flange " +
                                   std::to_string(with));
    queue.push_back(u);
  }
  for (std::size_t u = 0; u < nf; ++u) {
    if (w.placed[u]) continue;
    part.report.rigid_flanges.push_back(static_cast<int>(u));
    part.report.warnings.push_back("flange " + std::to_string(u) +
                                   " is attached to nothing: not moved");
  }
}

}  // namespace springscan::parts::detail
