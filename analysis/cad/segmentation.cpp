// Face adjacency graph, flanges and bends of a CAD part (rules in cad_segmentation.hpp).
#include "analysis/cad/segmentation.hpp"

#include <BRepClass_FaceClassifier.hxx>
#include <BRepGProp.hxx>
#include <BRepTools.hxx>
#include <GProp_GProps.hxx>
#include <TopExp.hxx>
#include <TopTools_IndexedDataMapOfShapeListOfShape.hxx>
#include <algorithm>
#include <cmath>
#include <map>
#include <numbers>
#include <set>

#include "analysis/cad/internal.hpp"
#include "analysis/cad/segmentation_internal.hpp"

namespace springscan::analysis {
namespace {

using Kind = AnalyticSurface::Kind;

void add_neighbors(const CadShape::Impl& impl, std::vector<CadFaceInfo>& infos) {
  TopTools_IndexedDataMapOfShapeListOfShape edge_faces;
  TopExp::MapShapesAndAncestors(impl.shape, TopAbs_EDGE, TopAbs_FACE, edge_faces);
  std::vector<std::set<int>> neighbors(infos.size());
  for (int e = 1; e <= edge_faces.Extent(); ++e) {
    std::vector<int> ids;
    for (const TopoDS_Shape& face : edge_faces(e)) ids.push_back(impl.faces.FindIndex(face) - 1);
    for (int a : ids)
      for (int b : ids)
        if (a != b && a >= 0 && b >= 0) neighbors[static_cast<std::size_t>(a)].insert(b);
  }
  for (std::size_t i = 0; i < infos.size(); ++i)
    infos[i].neighbors.assign(neighbors[i].begin(), neighbors[i].end());
}

CadFaceInfo describe_face(const CadShape::Impl& impl, int id) {
  CadFaceInfo info;
  info.id = id;
  GProp_GProps props;
  BRepGProp::SurfaceProperties(impl.face(id), props);
  info.area_mm2 = props.Mass();
  const gp_Pnt c = props.CentreOfMass();
  info.centroid = Vec3(c.X(), c.Y(), c.Z());
  const AnalyticSurface& s = impl.surfaces[static_cast<std::size_t>(id)];
  info.inner_point = info.centroid;
  double largest = -1.0;
  const CadMesh& mesh = impl.mesh;
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    if (mesh.triangle_faces[t] != id) continue;
    const auto& tri = mesh.triangles[t];
    const Vec3& a = mesh.vertices[tri[0]];
    const Vec3& b = mesh.vertices[tri[1]];
    const Vec3& c3 = mesh.vertices[tri[2]];
    const double area = (b - a).cross(c3 - a).norm();
    if (area > largest) largest = area, info.inner_point = (a + b + c3) / 3.0;
  }
  Vec3 foot;
  const Eigen::Vector2d uv = s.project(info.centroid, foot);
  if (s.kind == Kind::kPlane) {
    info.type = "plane";
    info.direction = s.normal(uv);
  } else if (s.kind == Kind::kCylinder) {
    info.type = "cylinder";
    info.direction = s.z.normalized();
    info.axis_point = s.origin + (info.centroid - s.origin).dot(info.direction) * info.direction;
    info.radius_mm = s.radius;
    const Vec3 on_axis = s.origin + (foot - s.origin).dot(info.direction) * info.direction;
    info.convex = s.normal(uv).dot(foot - on_axis) > 0.0;
  } else {
    info.type = "other";
  }
  return info;
}

}  // namespace

std::vector<CadFaceInfo> describe_faces(const CadShape& shape) {
  if (shape.empty()) return {};
  std::vector<CadFaceInfo> infos;
  for (int id = 0; id < shape.face_count(); ++id) infos.push_back(describe_face(shape.impl(), id));
  add_neighbors(shape.impl(), infos);
  return infos;
}

bool point_projects_into(const CadShape& shape, int face_id, const Vec3& p) {
  const CadShape::Impl& impl = shape.impl();
  const AnalyticSurface& s = impl.surfaces[static_cast<std::size_t>(face_id)];
  if (s.kind == Kind::kOther) return false;
  Vec3 foot;
  const Eigen::Vector2d uv = s.project(p, foot);
  BRepClass_FaceClassifier classifier(impl.face(face_id), gp_Pnt2d(uv.x(), uv.y()), 1e-7);
  return classifier.State() == TopAbs_IN || classifier.State() == TopAbs_ON;
}

double cylinder_sweep_deg(const CadShape& shape, int face_id) {
  double u0, u1, v0, v1;
  BRepTools::UVBounds(shape.impl().face(face_id), u0, u1, v0, v1);
  return (u1 - u0) * 180.0 / std::numbers::pi;
}

PartSegmentation segment_cad(const CadShape& shape, const CadSegmentationSettings& settings) {
  if (shape.empty()) return {};
  const auto infos = describe_faces(shape);
  const bool solid = shape.report().solids > 0;
  const auto flanges = find_flanges(shape, infos, solid, settings);
  PartSegmentation segmentation;
  segmentation.flanges = flanges.flanges;
  segmentation.bends = find_bends(shape, infos, flanges, solid, settings);
  std::vector<bool> used(infos.size(), false);
  for (const auto& f : segmentation.flanges)
    for (int id : f.face_ids) used[static_cast<std::size_t>(id)] = true;
  for (const auto& b : segmentation.bends)
    for (int id : b.face_ids) used[static_cast<std::size_t>(id)] = true;
  for (std::size_t i = 0; i < used.size(); ++i)
    if (!used[i]) segmentation.other_faces.push_back(static_cast<int>(i));
  return segmentation;
}

}  // namespace springscan::analysis
