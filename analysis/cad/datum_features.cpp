// Candidate datum features (rules in datum_features.hpp).
#include "analysis/cad/datum_features.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "analysis/cad/segmentation_internal.hpp"

namespace springscan::analysis {
namespace {

double deg(double rad) { return rad * 180.0 / std::numbers::pi; }

double angle_deg(const Vec3& a, const Vec3& b) {
  return deg(std::acos(std::clamp(std::abs(a.dot(b)), 0.0, 1.0)));
}

PadCandidate pad_of(const Flange& flange, const std::vector<CadFaceInfo>& faces) {
  PadCandidate pad{flange.id, flange.point, flange.normal, flange.area_mm2, flange.thickness_mm};
  double largest = -1.0;
  // The point of the flange's skin on `point`'s side: flange.point may lie in a hole.
  for (int id : flange.face_ids) {
    const CadFaceInfo& f = faces[static_cast<std::size_t>(id)];
    if (f.direction.dot(flange.normal) < 0.99 || f.area_mm2 <= largest) continue;
    largest = f.area_mm2;
    pad.point = f.inner_point - (f.inner_point - flange.point).dot(flange.normal) * flange.normal;
  }
  return pad;
}

// Concave cylinder faces of no bend, grouped by axis and radius and split into the sets of
// faces that meet (one group per hole, slot end or notch).
std::vector<std::vector<int>> hole_wall_groups(const std::vector<CadFaceInfo>& faces,
                                               const PartSegmentation& segmentation,
                                               const DatumCandidateSettings& s) {
  std::vector<bool> in_bend(faces.size(), false);
  for (const Bend& b : segmentation.bends)
    for (int id : b.face_ids) in_bend[static_cast<std::size_t>(id)] = true;
  std::vector<std::vector<int>> groups;
  for (const CadFaceInfo& f : faces) {
    if (f.type != "cylinder" || f.convex || in_bend[static_cast<std::size_t>(f.id)]) continue;
    const auto same = [&](const std::vector<int>& g) {
      const CadFaceInfo& h = faces[static_cast<std::size_t>(g.front())];
      const Vec3 off = f.axis_point - h.axis_point;
      return angle_deg(f.direction, h.direction) <= s.parallel_deg &&
             (off - off.dot(h.direction) * h.direction).norm() <= s.coaxial_mm &&
             std::abs(f.radius_mm - h.radius_mm) <= s.same_radius_mm;
    };
    const auto it = std::find_if(groups.begin(), groups.end(), same);
    if (it == groups.end())
      groups.push_back({f.id});
    else
      it->push_back(f.id);
  }
  // One hole's faces meet: coaxial faces apart are other holes on the axis (the side panel's two
  // walls have their slots' ends on common axes, whose half circles summed to a full one).
  std::vector<std::vector<int>> connected;
  for (const std::vector<int>& g : groups) {
    std::vector<bool> taken(g.size(), false);
    for (std::size_t seed = 0; seed < g.size(); ++seed) {
      if (taken[seed]) continue;
      std::vector<int> part = {g[seed]};
      taken[seed] = true;
      for (std::size_t k = 0; k < part.size(); ++k) {
        const std::vector<int>& next = faces[static_cast<std::size_t>(part[k])].neighbors;
        for (std::size_t j = 0; j < g.size(); ++j)
          if (!taken[j] && std::find(next.begin(), next.end(), g[j]) != next.end())
            taken[j] = true, part.push_back(g[j]);
      }
      connected.push_back(std::move(part));
    }
  }
  return connected;
}

// The flange a hole wall group goes through: a neighbouring skin whose normal is the axis.
const Flange* flange_through(const std::vector<int>& group, const std::vector<CadFaceInfo>& faces,
                             const PartSegmentation& segmentation,
                             const std::vector<int>& flange_of_face, double parallel_deg) {
  const Vec3& axis = faces[static_cast<std::size_t>(group.front())].direction;
  for (int id : group)
    for (int n : faces[static_cast<std::size_t>(id)].neighbors) {
      const int k = flange_of_face[static_cast<std::size_t>(n)];
      if (k < 0) continue;
      const Flange& f = segmentation.flanges[static_cast<std::size_t>(k)];
      if (angle_deg(f.normal, axis) <= parallel_deg) return &f;
    }
  return nullptr;
}

// A half-circle end of a slot: its axis point, and where its arc lies from the axis.
struct SlotEnd {
  const std::vector<int>* group = nullptr;
  const Flange* flange = nullptr;
  Vec3 axis_point = Vec3::Zero();
  Vec3 arc_side = Vec3::Zero();  // unit, across the axis, toward the arc's material-free side
  double radius = 0.0;
};

// Pairs the half-circle ends into slots: same flange and radius, each end's arc turned away from
// the other; each end with its nearest partner.
std::vector<SlotCandidate> pair_slot_ends(const std::vector<SlotEnd>& ends,
                                          const DatumCandidateSettings& s) {
  std::vector<SlotCandidate> slots;
  std::vector<bool> used(ends.size(), false);
  for (std::size_t i = 0; i < ends.size(); ++i) {
    if (used[i]) continue;
    const Vec3 n = ends[i].flange->normal;
    std::size_t best = ends.size();
    double best_distance = std::numeric_limits<double>::infinity();
    for (std::size_t j = 0; j < ends.size(); ++j) {
      if (j == i || used[j] || ends[j].flange != ends[i].flange ||
          std::abs(ends[j].radius - ends[i].radius) > s.same_radius_mm)
        continue;
      Vec3 d = ends[j].axis_point - ends[i].axis_point;
      d -= d.dot(n) * n;
      const double distance = d.norm();
      if (!(distance > s.coaxial_mm)) continue;
      // Each arc lies on the side away from the other end.
      if (!(ends[i].arc_side.dot(d) < 0.0 && ends[j].arc_side.dot(d) > 0.0)) continue;
      if (distance < best_distance) best_distance = distance, best = j;
    }
    if (best == ends.size()) continue;
    used[i] = used[best] = true;
    const SlotEnd& a = ends[i];
    const SlotEnd& b = ends[best];
    SlotCandidate slot;
    slot.face_ids = *a.group;
    slot.face_ids.insert(slot.face_ids.end(), b.group->begin(), b.group->end());
    slot.flange_id = a.flange->id;
    slot.axis = n;
    const Vec3 mid = 0.5 * (a.axis_point + b.axis_point);
    slot.centre = mid + (a.flange->point - mid).dot(n) * n;
    Vec3 along = b.axis_point - a.axis_point;
    along -= along.dot(n) * n;
    slot.direction = n.cross(along.normalized());
    slot.width_mm = a.radius + b.radius;
    slot.length_mm = best_distance + slot.width_mm;
    slot.thickness_mm = a.flange->thickness_mm;
    slots.push_back(std::move(slot));
  }
  return slots;
}

}  // namespace

DatumCandidates datum_candidates(const CadShape& shape, const std::vector<CadFaceInfo>& faces,
                                 const PartSegmentation& segmentation,
                                 const DatumCandidateSettings& settings) {
  DatumCandidates out;
  std::vector<int> flange_of_face(faces.size(), -1);
  for (std::size_t k = 0; k < segmentation.flanges.size(); ++k) {
    out.pads.push_back(pad_of(segmentation.flanges[k], faces));
    for (int id : segmentation.flanges[k].face_ids)
      flange_of_face[static_cast<std::size_t>(id)] = static_cast<int>(k);
  }
  std::sort(out.pads.begin(), out.pads.end(),
            [](const PadCandidate& a, const PadCandidate& b) { return a.area_mm2 > b.area_mm2; });
  const std::vector<std::vector<int>> groups = hole_wall_groups(faces, segmentation, settings);
  std::vector<SlotEnd> slot_ends;
  for (const std::vector<int>& group : groups) {
    const CadFaceInfo& wall = faces[static_cast<std::size_t>(group.front())];
    double sweep = 0.0;
    for (int id : group) sweep += cylinder_sweep_deg(shape, id);
    const Flange* through =
        flange_through(group, faces, segmentation, flange_of_face, settings.parallel_deg);
    if (!through) continue;
    if (std::abs(sweep - 180.0) <= settings.half_circle_tolerance_deg) {
      Vec3 side = wall.inner_point - wall.axis_point;
      side -= side.dot(through->normal) * through->normal;
      if (side.norm() > 0.0)
        slot_ends.push_back({&group, through, wall.axis_point, side.normalized(), wall.radius_mm});
      continue;
    }
    if (sweep < settings.full_circle_deg) continue;  // a notch or a rounded corner
    HoleCandidate hole;
    hole.face_ids = group;
    hole.flange_id = through->id;
    hole.axis = through->normal;
    hole.centre = wall.axis_point + (through->point - wall.axis_point).dot(hole.axis) * hole.axis;
    hole.diameter_mm = 2.0 * wall.radius_mm;
    hole.thickness_mm = through->thickness_mm;
    out.holes.push_back(std::move(hole));
  }
  std::sort(out.holes.begin(), out.holes.end(), [](const HoleCandidate& a, const HoleCandidate& b) {
    return a.diameter_mm > b.diameter_mm;
  });
  out.slots = pair_slot_ends(slot_ends, settings);
  std::sort(out.slots.begin(), out.slots.end(), [](const SlotCandidate& a, const SlotCandidate& b) {
    return a.length_mm > b.length_mm;
  });
  return out;
}

}  // namespace springscan::analysis
