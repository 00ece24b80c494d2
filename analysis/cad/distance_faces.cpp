// Per-face work of the exact distance: UV point location, boundary edges, and the closest point
// of one face (closed form for planes and cylinders, Extrema for other surfaces).
#include <BRepAdaptor_Curve.hxx>
#include <BRepAdaptor_Surface.hxx>
#include <BRepLProp_SLProps.hxx>
#include <BRep_Tool.hxx>
#include <Extrema_ExtPC.hxx>
#include <Extrema_GenLocateExtPS.hxx>
#include <Extrema_POnCurv.hxx>
#include <GeomAPI_ProjectPointOnSurf.hxx>
#include <TopExp_Explorer.hxx>
#include <algorithm>
#include <cmath>
#include <numbers>

#include "analysis/cad/distance_internal.hpp"

namespace springscan::analysis {
namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;

double cross2(const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  return a.x() * b.y() - a.y() * b.x();
}

bool in_triangle(const std::array<Eigen::Vector2d, 3>& t, const Eigen::Vector2d& p) {
  const double area = cross2(t[1] - t[0], t[2] - t[0]);
  if (!(std::abs(area) > 0.0)) return false;
  const double tol = -1e-9 * std::abs(area);
  const double s = area > 0 ? 1.0 : -1.0;
  return s * cross2(t[1] - t[0], p - t[0]) >= tol && s * cross2(t[2] - t[1], p - t[1]) >= tol &&
         s * cross2(t[0] - t[2], p - t[2]) >= tol;
}

Vec3 v3(const gp_Pnt& p) { return {p.X(), p.Y(), p.Z()}; }

// Periodic u of a cylinder moved into the period starting just below the face's u_min.
Eigen::Vector2d wrap_uv(const FaceData& face, Eigen::Vector2d uv) {
  if (face.surface.kind != AnalyticSurface::Kind::kCylinder) return uv;
  const double start = face.grid.u_min() - 1e-9;
  uv.x() -= kTwoPi * std::floor((uv.x() - start) / kTwoPi);
  return uv;
}

// Inside the trimmed face: in its UV triangulation; near curved trims (in the UV box but in no
// triangle) the exact classifier decides.
bool inside_face(const CadShape::Impl& shape, const FaceData& face, int face_id,
                 const Eigen::Vector2d& uv) {
  const int triangle = face.grid.locate(uv);
  if (triangle < 0 && !face.grid.in_box(uv, 1e-9)) return false;
  return inside_trimmed(shape, face_id, triangle, uv);
}

Vec3 normal_at(const CadShape::Impl& shape, const FaceData& face, int face_id, const Vec3& p) {
  if (face.surface.kind != AnalyticSurface::Kind::kOther) {
    Vec3 foot;
    return face.surface.normal(face.surface.project(p, foot));
  }
  GeomAPI_ProjectPointOnSurf projection(gp_Pnt(p.x(), p.y(), p.z()),
                                        BRep_Tool::Surface(shape.face(face_id)));
  if (projection.NbPoints() == 0) return Vec3::UnitZ();
  double u, v;
  projection.LowerDistanceParameters(u, v);
  const BRepAdaptor_Surface surface(shape.face(face_id), false);
  BRepLProp_SLProps props(surface, u, v, 1, 1e-9);
  if (!props.IsNormalDefined()) return Vec3::UnitZ();
  const gp_Dir n = props.Normal();
  return face.surface.sense * Vec3(n.X(), n.Y(), n.Z());
}

// Closest point of one boundary edge: a segment in closed form, any other curve by Extrema's
// global point-curve extrema (all local minima, and the ends).
Vec3 closest_on_circle(const EdgeData& edge, const Vec3& q) {
  const Vec3 w = q - edge.center;
  const double cx = w.dot(edge.x), cy = w.dot(edge.y);
  const Vec3 nearer_end =
      (edge.a - q).squaredNorm() <= (edge.b - q).squaredNorm() ? edge.a : edge.b;
  if (cx * cx + cy * cy == 0.0) return nearer_end;  // on the axis: every point is as close
  double t = std::atan2(cy, cx);
  t -= kTwoPi * std::floor((t - edge.t0) / kTwoPi);  // into [t0, t0 + 2 pi)
  if (t > edge.t1) return nearer_end;
  return edge.center + edge.radius * (std::cos(t) * edge.x + std::sin(t) * edge.y);
}

Vec3 closest_on_edge(const DistanceTables& tables, const EdgeData& edge, const Vec3& q) {
  const Vec3 d = edge.b - edge.a;
  if (edge.kind == EdgeData::Kind::kCircle) return closest_on_circle(edge, q);
  if (edge.kind == EdgeData::Kind::kLine) {
    const double t =
        d.squaredNorm() > 0 ? std::clamp((q - edge.a).dot(d) / d.squaredNorm(), 0.0, 1.0) : 0.0;
    return edge.a + t * d;
  }
  Vec3 result = (edge.a - q).squaredNorm() <= (edge.b - q).squaredNorm() ? edge.a : edge.b;
  const BRepAdaptor_Curve curve(TopoDS::Edge(tables.edge_map(edge.edge_index)));
  Extrema_ExtPC extrema(gp_Pnt(q.x(), q.y(), q.z()), curve);
  if (!extrema.IsDone()) return result;
  for (int i = 1; i <= extrema.NbExt(); ++i) {
    const Vec3 p = v3(extrema.Point(i).Value());
    if ((p - q).squaredNorm() < (result - q).squaredNorm()) result = p;
  }
  return result;
}

FaceFoot on_boundary(const CadShape::Impl& shape, const DistanceTables& tables, int face_id,
                     const Vec3& q) {
  const FaceData& face = tables.faces[static_cast<std::size_t>(face_id)];
  FaceFoot best;
  for (int e : face.edges) {
    const Vec3 p = closest_on_edge(tables, tables.edges[static_cast<std::size_t>(e)], q);
    const double d = (p - q).norm();
    if (!best.valid || d < best.distance) best = {true, p, Vec3::UnitZ(), d};
  }
  if (best.valid) best.normal = normal_at(shape, face, face_id, best.point);
  return best;
}

FaceFoot on_general_surface(const CadShape::Impl& shape, const FaceData& face, int face_id,
                            const Vec3& q, const TriangleFoot& seed, bool& inside) {
  const auto& tri = shape.mesh.triangles[seed.triangle];
  const Eigen::Vector2d uv0 = seed.barycentric.x() * shape.mesh.uv[tri[0]] +
                              seed.barycentric.y() * shape.mesh.uv[tri[1]] +
                              seed.barycentric.z() * shape.mesh.uv[tri[2]];
  const BRepAdaptor_Surface surface(shape.face(face_id));
  Extrema_GenLocateExtPS locate(surface, 1e-9, 1e-9);
  locate.Perform(gp_Pnt(q.x(), q.y(), q.z()), uv0.x(), uv0.y());
  Eigen::Vector2d uv = uv0;
  if (locate.IsDone()) locate.Point().Parameter(uv.x(), uv.y());
  inside = inside_face(shape, face, face_id, uv);
  BRepLProp_SLProps props(surface, uv.x(), uv.y(), 1, 1e-9);
  FaceFoot foot{true, v3(props.Value()), Vec3::UnitZ(), 0.0};
  if (props.IsNormalDefined()) {
    const gp_Dir n = props.Normal();
    foot.normal = face.surface.sense * Vec3(n.X(), n.Y(), n.Z());
  }
  foot.distance = (foot.point - q).norm();
  return foot;
}

}  // namespace

void UvGrid::build(std::vector<std::array<Eigen::Vector2d, 3>> triangles,
                   std::vector<std::uint32_t> ids) {
  triangles_ = std::move(triangles);
  ids_ = std::move(ids);
  if (triangles_.empty()) return;
  lo_ = hi_ = triangles_[0][0];
  for (const auto& t : triangles_)
    for (const auto& p : t) lo_ = lo_.cwiseMin(p), hi_ = hi_.cwiseMax(p);
  const int n = std::clamp(static_cast<int>(std::sqrt(triangles_.size() / 2.0)) + 1, 1, 256);
  nu_ = nv_ = n;
  cell_ = ((hi_ - lo_) / n).cwiseMax(Eigen::Vector2d::Constant(1e-300));
  std::vector<std::vector<std::uint32_t>> cells(static_cast<std::size_t>(n * n));
  const auto index = [&](const Eigen::Vector2d& p, int axis) {
    const int count = axis == 0 ? nu_ : nv_;
    return std::clamp(static_cast<int>((p[axis] - lo_[axis]) / cell_[axis]), 0, count - 1);
  };
  for (std::uint32_t i = 0; i < triangles_.size(); ++i) {
    Eigen::Vector2d a = triangles_[i][0], b = a;
    for (const auto& p : triangles_[i]) a = a.cwiseMin(p), b = b.cwiseMax(p);
    for (int cu = index(a, 0); cu <= index(b, 0); ++cu)
      for (int cv = index(a, 1); cv <= index(b, 1); ++cv)
        cells[static_cast<std::size_t>(cv * nu_ + cu)].push_back(i);
  }
  start_.assign(1, 0);
  for (const auto& cell : cells) {
    items_.insert(items_.end(), cell.begin(), cell.end());
    start_.push_back(static_cast<std::uint32_t>(items_.size()));
  }
}

bool UvGrid::in_box(const Eigen::Vector2d& uv, double margin) const {
  return !triangles_.empty() && (uv.array() >= lo_.array() - margin).all() &&
         (uv.array() <= hi_.array() + margin).all();
}

int UvGrid::locate(const Eigen::Vector2d& uv) const {
  const Eigen::Vector2d margin = 1e-9 * (hi_ - lo_).cwiseMax(Eigen::Vector2d::Ones());
  if (triangles_.empty() || (uv.array() < (lo_ - margin).array()).any() ||
      (uv.array() > (hi_ + margin).array()).any())
    return -1;
  const int cu = std::clamp(static_cast<int>((uv.x() - lo_.x()) / cell_.x()), 0, nu_ - 1);
  const int cv = std::clamp(static_cast<int>((uv.y() - lo_.y()) / cell_.y()), 0, nv_ - 1);
  const auto c = static_cast<std::size_t>(cv * nu_ + cu);
  for (std::uint32_t k = start_[c]; k < start_[c + 1]; ++k)
    if (in_triangle(triangles_[items_[k]], uv)) return static_cast<int>(ids_[items_[k]]);
  return -1;
}

DistanceTables build_distance_tables(const CadShape::Impl& shape, double margin_mm) {
  DistanceTables tables;
  const int face_count = shape.faces.Extent();
  tables.faces.resize(static_cast<std::size_t>(face_count));
  std::vector<std::vector<std::array<Eigen::Vector2d, 3>>> uv(tables.faces.size());
  std::vector<std::vector<std::uint32_t>> ids(tables.faces.size());
  for (std::size_t t = 0; t < shape.mesh.triangles.size(); ++t) {
    const auto& tri = shape.mesh.triangles[t];
    const auto f = static_cast<std::size_t>(shape.mesh.triangle_faces[t]);
    uv[f].push_back({shape.mesh.uv[tri[0]], shape.mesh.uv[tri[1]], shape.mesh.uv[tri[2]]});
    ids[f].push_back(static_cast<std::uint32_t>(t));
  }
  for (int f = 0; f < face_count; ++f) {
    FaceData& face = tables.faces[static_cast<std::size_t>(f)];
    face.surface = shape.surfaces[static_cast<std::size_t>(f)];
    face.grid.build(std::move(uv[static_cast<std::size_t>(f)]),
                    std::move(ids[static_cast<std::size_t>(f)]));
    face.slack_mm = 2.0 * shape.mesh.face_deflection_mm[static_cast<std::size_t>(f)] + margin_mm;
    for (TopExp_Explorer it(shape.face(f), TopAbs_EDGE); it.More(); it.Next()) {
      const TopoDS_Edge& edge = TopoDS::Edge(it.Current());
      if (BRep_Tool::Degenerated(edge) || !BRep_Tool::IsGeometric(edge)) continue;
      const int before = tables.edge_map.Extent();
      const int index = tables.edge_map.Add(edge);
      if (index > before) {
        EdgeData data;
        data.edge_index = index;
        const BRepAdaptor_Curve curve(edge);
        data.a = v3(curve.Value(curve.FirstParameter()));
        data.b = v3(curve.Value(curve.LastParameter()));
        if (curve.GetType() == GeomAbs_Line) {
          data.kind = EdgeData::Kind::kLine;
        } else if (curve.GetType() == GeomAbs_Circle &&
                   curve.LastParameter() - curve.FirstParameter() <= kTwoPi + 1e-12) {
          const gp_Circ circle = curve.Circle();  // location applied by the adaptor
          data.kind = EdgeData::Kind::kCircle;
          data.center = v3(circle.Location());
          data.x = Vec3(circle.XAxis().Direction().X(), circle.XAxis().Direction().Y(),
                        circle.XAxis().Direction().Z());
          data.y = Vec3(circle.YAxis().Direction().X(), circle.YAxis().Direction().Y(),
                        circle.YAxis().Direction().Z());
          data.radius = circle.Radius();
          data.t0 = curve.FirstParameter();
          data.t1 = curve.LastParameter();
        }
        tables.edges.push_back(std::move(data));
      }
      const int slot = index - 1;
      if (std::find(face.edges.begin(), face.edges.end(), slot) == face.edges.end())
        face.edges.push_back(slot);
    }
  }
  return tables;
}

FaceFoot foot_on_face(const CadShape::Impl& shape, const DistanceTables& tables, int face_id,
                      const Vec3& q, const TriangleFoot& seed) {
  const FaceData& face = tables.faces[static_cast<std::size_t>(face_id)];
  bool inside = false;
  FaceFoot foot;
  if (face.surface.kind == AnalyticSurface::Kind::kOther) {
    foot = on_general_surface(shape, face, face_id, q, seed, inside);
  } else {
    Vec3 point;
    const Eigen::Vector2d uv = wrap_uv(face, face.surface.project(q, point));
    inside = inside_face(shape, face, face_id, uv);
    foot = {true, point, face.surface.normal(uv), (point - q).norm()};
  }
  if (inside) return foot;
  return on_boundary(shape, tables, face_id, q);
}

}  // namespace springscan::analysis
