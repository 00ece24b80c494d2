// Candidate datum features (rules in datum_features.hpp).
#include "analysis/cad/datum_features.hpp"

#include <algorithm>
#include <cmath>
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

// Concave cylinder faces of no bend, grouped by axis and radius (one group per hole or notch).
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
  return groups;
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
  for (const std::vector<int>& group : hole_wall_groups(faces, segmentation, settings)) {
    const CadFaceInfo& wall = faces[static_cast<std::size_t>(group.front())];
    double sweep = 0.0;
    for (int id : group) sweep += cylinder_sweep_deg(shape, id);
    if (sweep < settings.full_circle_deg) continue;  // a notch or a rounded corner
    // The flange the hole goes through: a neighbouring skin whose normal is the axis.
    const Flange* through = nullptr;
    for (int id : group)
      for (int n : faces[static_cast<std::size_t>(id)].neighbors) {
        const int k = flange_of_face[static_cast<std::size_t>(n)];
        if (k < 0 || through) continue;
        const Flange& f = segmentation.flanges[static_cast<std::size_t>(k)];
        if (angle_deg(f.normal, wall.direction) <= settings.parallel_deg) through = &f;
      }
    if (!through) continue;
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
  return out;
}

}  // namespace springscan::analysis
