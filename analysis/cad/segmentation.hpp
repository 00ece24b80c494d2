#pragma once
// The CAD part segmented into flanges and bends (DESIGN.md stages 6-7: the local best
// fits run on the flanges, springback is measured at the bends).

#include <string>
#include <vector>

#include "analysis/cad/import.hpp"
#include "analysis/core/part_model.hpp"

namespace springscan::analysis {

struct CadSegmentationSettings {
  double coplanar_angle_deg = 0.5;     ///< normals within this angle count as parallel
  double coplanar_distance_mm = 0.02;  ///< and planes within this offset as one plane
  double coaxial_distance_mm = 0.05;   ///< cylinder axes closer than this are one axis
  double same_radius_mm = 0.02;        ///< split cylinder faces of one bend share the radius
  /// Solids: two opposite planar groups at most this far apart, back to back (material between
  /// them) and overlapping, are the two sides of one flange.
  double max_sheet_thickness_mm = 6.0;
};

/// What one face is, for `springscan model` and for logs.
struct CadFaceInfo {
  int id = 0;
  std::string type;  ///< "plane", "cylinder" or "other"
  double area_mm2 = 0.0;
  Vec3 centroid = Vec3::Zero();     ///< area centroid (may lie off the face, e.g. in a hole)
  Vec3 inner_point = Vec3::Zero();  ///< a point of the face: its largest triangle's centroid
  Vec3 direction = Vec3::UnitZ();   ///< planes: outward normal; cylinders: axis direction
  Vec3 axis_point = Vec3::Zero();   ///< cylinders: a point on the axis
  double radius_mm = 0.0;           ///< cylinders
  bool convex = false;              ///< cylinders: outward normal points away from the axis
  std::vector<int> neighbors;       ///< faces sharing an edge, ascending
};

/// Per face: its type, area, geometry and neighbours (the face adjacency graph, built with
/// TopExp::MapShapesAndAncestors over the edges). Face ids as in CadShape. Empty for an empty
/// shape.
std::vector<CadFaceInfo> describe_faces(const CadShape& shape);

/// Flanges, bends and the remaining faces. Rules (docs/cad-model.md):
///  - adjacent planar faces with parallel outward normals on one plane merge into a group;
///  - on a solid, two groups with opposite normals, back to back at most max_sheet_thickness_mm
///    (and at most the square root of the smaller area) apart, of similar area (ratio >= 1/2)
///    and overlapping (a point of one projects into the other), are one flange; an unpaired planar
///    group of a solid (a sheet edge, a cut face) is an "other" face; on a shell every planar group
///    is a flange;
///  - adjacent cylindrical faces on one axis with one radius merge; groups with parallel axes
///    joining the same two flanges (inner and outer side of a solid bend) merge into one bend;
///  - a cylinder group touching exactly two flanges, its axis parallel to both, is a bend: axis =
///  the cylinder axis through
///    the projection of the group's centroid; radius = inner bend radius (the concave side's
///    radius, or the convex radius minus the sheet thickness when only the outer side is round);
///    nominal angle = the angle between the two flanges' normals taken on the same side of the
///    sheet (the planar faces beside one cylinder face), i.e. the angle the sheet turns.
/// Ids: flanges and bends numbered from 0 in order of their smallest face id.
PartSegmentation segment_cad(const CadShape& shape, const CadSegmentationSettings& settings = {});

}  // namespace springscan::analysis
