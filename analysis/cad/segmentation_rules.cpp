// The grouping rules of segment_cad (cad_segmentation.hpp): planar groups, sheet sides paired
// into flanges, cylinder groups into bends. Pure geometry over CadFaceInfo.
#include <algorithm>
#include <cmath>
#include <map>
#include <numbers>
#include <numeric>
#include <set>

#include "analysis/cad/segmentation_internal.hpp"

namespace springscan::analysis {
namespace {

constexpr double kRadToDeg = 180.0 / std::numbers::pi;

// Union-find whose roots are the smallest member, so groups are named by their first face.
struct Groups {
  explicit Groups(std::size_t n) : parent(n) { std::iota(parent.begin(), parent.end(), 0); }
  int find(int i) {
    while (parent[static_cast<std::size_t>(i)] != i)
      i = parent[static_cast<std::size_t>(i)] =
          parent[static_cast<std::size_t>(parent[static_cast<std::size_t>(i)])];
    return i;
  }
  void unite(int a, int b) {
    a = find(a), b = find(b);
    if (a != b) parent[static_cast<std::size_t>(std::max(a, b))] = std::min(a, b);
  }
  std::map<int, std::vector<int>> members(const std::vector<bool>& include) {
    std::map<int, std::vector<int>> out;
    for (std::size_t i = 0; i < parent.size(); ++i)
      if (include[i]) out[find(static_cast<int>(i))].push_back(static_cast<int>(i));
    return out;
  }
  std::vector<int> parent;
};

struct PlaneGroup {
  std::vector<int> faces;
  Vec3 normal = Vec3::UnitZ();
  Vec3 point = Vec3::Zero();  ///< a point of the largest face

  double area = 0.0;
  int largest = 0;
};

PlaneGroup make_plane_group(const std::vector<CadFaceInfo>& infos, std::vector<int> faces) {
  PlaneGroup g;
  g.faces = std::move(faces);
  g.largest = g.faces.front();
  for (int f : g.faces) {
    g.area += infos[static_cast<std::size_t>(f)].area_mm2;
    if (infos[static_cast<std::size_t>(f)].area_mm2 >
        infos[static_cast<std::size_t>(g.largest)].area_mm2)
      g.largest = f;
  }
  g.normal = infos[static_cast<std::size_t>(g.largest)].direction;
  g.point = infos[static_cast<std::size_t>(g.largest)].inner_point;
  return g;
}

// Two sides of one sheet: opposite outward normals, back to back (each lies behind the other's
// outward normal, material between), no farther apart than a sheet, and overlapping.
bool sheet_sides(const CadShape& shape, const PlaneGroup& a, const PlaneGroup& b,
                 const CadSegmentationSettings& settings, double& thickness) {
  if (a.normal.dot(b.normal) > -std::cos(settings.coplanar_angle_deg / kRadToDeg)) return false;
  const double offset = (b.point - a.point).dot(a.normal);  // < 0: b lies behind a
  thickness = -offset;
  if (!(thickness > settings.coplanar_distance_mm && thickness <= settings.max_sheet_thickness_mm))
    return false;
  // A sheet's two sides are alike: similar areas, far wider than the sheet is thick.
  const double small = std::min(a.area, b.area), large = std::max(a.area, b.area);
  if (small < 0.5 * large || thickness > std::sqrt(small)) return false;
  for (int f : a.faces)
    if (point_projects_into(shape, f, b.point)) return true;
  for (int f : b.faces)
    if (point_projects_into(shape, f, a.point)) return true;
  return false;
}

bool coaxial(const CadFaceInfo& a, const CadFaceInfo& b, const CadSegmentationSettings& s) {
  if (std::abs(a.direction.dot(b.direction)) < std::cos(s.coplanar_angle_deg / kRadToDeg))
    return false;
  const Vec3 w = b.axis_point - a.axis_point;
  return (w - w.dot(a.direction) * a.direction).norm() <= s.coaxial_distance_mm;
}

// Axis directions are only defined up to sign: make the largest component positive.
Vec3 canonical_direction(Vec3 d) {
  int k = 0;
  d.cwiseAbs().maxCoeff(&k);
  return d[k] < 0 ? Vec3(-d) : d;
}

}  // namespace

FlangeTable find_flanges(const CadShape& shape, const std::vector<CadFaceInfo>& infos, bool solid,
                         const CadSegmentationSettings& settings) {
  const double cos_tol = std::cos(settings.coplanar_angle_deg / kRadToDeg);
  Groups groups(infos.size());
  std::vector<bool> planar(infos.size());
  for (const auto& f : infos) {
    planar[static_cast<std::size_t>(f.id)] = f.type == "plane";
    for (int n : f.neighbors) {
      const auto& g = infos[static_cast<std::size_t>(n)];
      if (f.type != "plane" || g.type != "plane" || f.direction.dot(g.direction) < cos_tol)
        continue;
      if (std::abs((g.centroid - f.centroid).dot(f.direction)) <= settings.coplanar_distance_mm)
        groups.unite(f.id, n);
    }
  }
  std::vector<PlaneGroup> planes;
  for (auto& [root, members] : groups.members(planar))
    planes.push_back(make_plane_group(infos, members));
  // Pair the sides of each solid sheet, the thinnest partner first.
  std::vector<int> partner(planes.size(), -1);
  std::vector<double> pair_thickness(planes.size(), 0.0);
  for (std::size_t i = 0; solid && i < planes.size(); ++i) {
    for (std::size_t j = i + 1; j < planes.size(); ++j) {
      double t = 0.0;
      if (partner[j] >= 0 || !sheet_sides(shape, planes[i], planes[j], settings, t)) continue;
      if (partner[i] >= 0 && pair_thickness[i] <= t) continue;
      if (partner[i] >= 0) partner[static_cast<std::size_t>(partner[i])] = -1;
      partner[i] = static_cast<int>(j), partner[j] = static_cast<int>(i);
      pair_thickness[i] = pair_thickness[j] = t;
    }
  }
  FlangeTable table;
  table.flange_of_face.assign(infos.size(), -1);
  for (std::size_t i = 0; i < planes.size(); ++i) {
    const int j = partner[i];
    if (j >= 0 && static_cast<std::size_t>(j) < i) continue;  // added with its partner
    if (solid && j < 0) continue;                             // a sheet edge or cut face: "other"
    // The reported side: the larger one (ties: the first face).
    const bool other_side =
        j >= 0 && planes[static_cast<std::size_t>(j)].area > planes[i].area + 1e-9;
    const PlaneGroup& side = other_side ? planes[static_cast<std::size_t>(j)] : planes[i];
    Flange flange;
    flange.id = static_cast<int>(table.flanges.size());
    flange.face_ids = planes[i].faces;
    if (j >= 0) {
      const auto& more = planes[static_cast<std::size_t>(j)].faces;
      flange.face_ids.insert(flange.face_ids.end(), more.begin(), more.end());
      std::sort(flange.face_ids.begin(), flange.face_ids.end());
    }
    flange.point = side.point;
    flange.normal = side.normal;
    flange.area_mm2 = side.area;
    flange.thickness_mm = j >= 0 ? pair_thickness[i] : 0.0;
    for (int f : flange.face_ids) table.flange_of_face[static_cast<std::size_t>(f)] = flange.id;
    table.flanges.push_back(std::move(flange));
  }
  return table;
}

namespace {

// Cylinder faces grouped by axis and radius (split faces of one cylinder).
std::map<int, std::vector<int>> cylinder_groups(const std::vector<CadFaceInfo>& infos,
                                                const CadSegmentationSettings& settings) {
  Groups groups(infos.size());
  std::vector<bool> cylindrical(infos.size());
  for (const auto& f : infos) {
    cylindrical[static_cast<std::size_t>(f.id)] = f.type == "cylinder";
    for (int n : f.neighbors) {
      const auto& g = infos[static_cast<std::size_t>(n)];
      if (f.type == "cylinder" && g.type == "cylinder" && coaxial(f, g, settings) &&
          std::abs(f.radius_mm - g.radius_mm) <= settings.same_radius_mm)
        groups.unite(f.id, n);
    }
  }
  return groups.members(cylindrical);
}

// The flanges a cylinder group touches, when it is a bend between two of them: exactly two,
// with its axis parallel to both (a hole's axis crosses its flange). Empty otherwise.
std::set<int> bend_flanges(const std::vector<int>& members, const std::vector<CadFaceInfo>& infos,
                           const FlangeTable& flanges, const CadSegmentationSettings& settings) {
  std::set<int> touched;
  for (int f : members)
    for (int n : infos[static_cast<std::size_t>(f)].neighbors)
      if (flanges.flange_of_face[static_cast<std::size_t>(n)] >= 0)
        touched.insert(flanges.flange_of_face[static_cast<std::size_t>(n)]);
  if (touched.size() != 2) return {};
  const Vec3& axis = infos[static_cast<std::size_t>(members.front())].direction;
  const double sin_tol = std::sin(settings.coplanar_angle_deg / kRadToDeg);
  for (int flange : touched)
    if (std::abs(axis.dot(flanges.flanges[static_cast<std::size_t>(flange)].normal)) > sin_tol)
      return {};
  return touched;
}

using BendCandidate = std::pair<std::vector<int>, std::set<int>>;  // faces, the two flanges

// Each cylinder group that joins two flanges; groups joining the same two flanges (the inner
// and outer side of one solid bend) merge.
std::vector<BendCandidate> bend_candidates(const std::vector<CadFaceInfo>& infos,
                                           const FlangeTable& flanges,
                                           const CadSegmentationSettings& settings) {
  std::vector<BendCandidate> candidates;
  for (auto& [root, members] : cylinder_groups(infos, settings)) {
    const std::set<int> touched = bend_flanges(members, infos, flanges, settings);
    if (touched.empty()) continue;
    bool merged = false;
    for (auto& [faces, pair] : candidates) {
      // Two flanges share at most one bend: merge whatever joins the same pair, also when the
      // two sides' arcs are not coaxial (a sheet modelled as one surface moved by the
      // thickness, like the roof sheet of SOURCES.md), as long as the axes are parallel.
      const Vec3& d0 = infos[static_cast<std::size_t>(faces.front())].direction;
      const Vec3& d1 = infos[static_cast<std::size_t>(members.front())].direction;
      if (pair != touched ||
          std::abs(d0.dot(d1)) < std::cos(settings.coplanar_angle_deg / kRadToDeg))
        continue;
      faces.insert(faces.end(), members.begin(), members.end());
      std::sort(faces.begin(), faces.end());
      merged = true;
      break;
    }
    if (!merged) candidates.emplace_back(members, touched);
  }
  return candidates;
}

// A bend's axis (through the projection of its area centroid) and inner radius.
void bend_geometry(const std::vector<CadFaceInfo>& infos, const FlangeTable& flanges, bool solid,
                   Bend& bend) {
  const CadFaceInfo& first = infos[static_cast<std::size_t>(bend.face_ids.front())];
  bend.axis_direction = canonical_direction(first.direction);
  Vec3 centroid = Vec3::Zero();
  double area = 0.0, concave = INFINITY, convex = INFINITY;
  for (int f : bend.face_ids) {
    const auto& info = infos[static_cast<std::size_t>(f)];
    centroid += info.area_mm2 * info.centroid;
    area += info.area_mm2;
    (info.convex ? convex : concave) = std::min(info.convex ? convex : concave, info.radius_mm);
  }
  centroid /= std::max(area, 1e-300);
  bend.axis_point = first.axis_point +
                    (centroid - first.axis_point).dot(bend.axis_direction) * bend.axis_direction;
  // Inner radius: a shell has one surface; a solid's concave side is the inside of the bend,
  // and with only a rounded outside the inside is the outer radius minus the thickness.
  const double t = std::max(flanges.flanges[static_cast<std::size_t>(bend.flange_a)].thickness_mm,
                            flanges.flanges[static_cast<std::size_t>(bend.flange_b)].thickness_mm);
  if (!solid)
    bend.radius_mm = std::min(concave, convex);
  else
    bend.radius_mm = std::isfinite(concave) ? concave : std::max(convex - t, 0.0);
}

}  // namespace

std::vector<Bend> find_bends(const CadShape& shape, const std::vector<CadFaceInfo>& infos,
                             const FlangeTable& flanges, bool solid,
                             const CadSegmentationSettings& settings) {
  std::vector<Bend> bends;
  for (const auto& [faces, pair] : bend_candidates(infos, flanges, settings)) {
    Bend bend;
    bend.id = static_cast<int>(bends.size());
    bend.face_ids = faces;
    bend.flange_a = *pair.begin();
    bend.flange_b = *pair.rbegin();
    bend_geometry(infos, flanges, solid, bend);
    bend.nominal_angle_deg = bend_angle_deg(shape, infos, flanges, bend);
    bends.push_back(std::move(bend));
  }
  return bends;
}

double bend_angle_deg(const CadShape& shape, const std::vector<CadFaceInfo>& infos,
                      const FlangeTable& flanges, const Bend& bend) {
  // Planar faces of both flanges beside one cylinder face lie on the same side of the sheet:
  // the angle between their outward normals is the angle the sheet turns.
  for (int c : bend.face_ids) {
    const CadFaceInfo* a = nullptr;
    const CadFaceInfo* b = nullptr;
    for (int n : infos[static_cast<std::size_t>(c)].neighbors) {
      const int flange = flanges.flange_of_face[static_cast<std::size_t>(n)];
      if (flange == bend.flange_a && !a) a = &infos[static_cast<std::size_t>(n)];
      if (flange == bend.flange_b && !b) b = &infos[static_cast<std::size_t>(n)];
    }
    if (a && b) return std::acos(std::clamp(a->direction.dot(b->direction), -1.0, 1.0)) * kRadToDeg;
  }
  return cylinder_sweep_deg(shape, bend.face_ids.front());
}

}  // namespace springscan::analysis
