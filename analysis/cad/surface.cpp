// Closed forms of planar and cylindrical faces (AnalyticSurface, cad_internal.hpp), used by the
// exact distance and the segmentation without calling OpenCASCADE per query.
#include <BRep_Tool.hxx>
#include <Geom_Circle.hxx>
#include <Geom_CylindricalSurface.hxx>
#include <Geom_Line.hxx>
#include <Geom_Plane.hxx>
#include <Geom_RectangularTrimmedSurface.hxx>
#include <Geom_SurfaceOfLinearExtrusion.hxx>
#include <Geom_SurfaceOfRevolution.hxx>
#include <Geom_TrimmedCurve.hxx>
#include <cmath>

#include "analysis/cad/internal.hpp"

namespace springscan::analysis {
namespace {

constexpr double kParallel = 1e-12;  // 1 - |cos| below which two directions count as parallel

Vec3 v3(const gp_XYZ& p) { return {p.X(), p.Y(), p.Z()}; }

Handle(Geom_Curve) unwrap(Handle(Geom_Curve) curve) {
  while (auto trimmed = Handle(Geom_TrimmedCurve)::DownCast(curve)) curve = trimmed->BasisCurve();
  return curve;
}

void set_frame(AnalyticSurface& s, const gp_Ax3& ax) {
  s.origin = v3(ax.Location().XYZ());
  s.x = v3(ax.XDirection().XYZ());
  s.y = v3(ax.YDirection().XYZ());
  s.z = v3(ax.Direction().XYZ());
}

// A surface of revolution of a line parallel to its axis is a cylinder (IGES type 120).
bool from_revolution(const Geom_SurfaceOfRevolution& rev, AnalyticSurface& s) {
  const auto line = Handle(Geom_Line)::DownCast(unwrap(rev.BasisCurve()));
  if (line.IsNull()) return false;
  const Vec3 axis_point = v3(rev.Axis().Location().XYZ()), axis = v3(rev.Axis().Direction().XYZ());
  const Vec3 l0 = v3(line->Position().Location().XYZ()), d = v3(line->Position().Direction().XYZ());
  if (1.0 - std::abs(d.dot(axis)) > kParallel) return false;
  const Vec3 radial = (l0 - axis_point) - (l0 - axis_point).dot(axis) * axis;
  if (!(radial.norm() > 1e-9)) return false;
  s.kind = AnalyticSurface::Kind::kCylinder;
  s.origin = axis_point;
  s.z = axis;
  s.x = radial.normalized();
  s.y = s.z.cross(s.x);  // rotation by +u about the axis
  s.radius = radial.norm();
  s.v_offset = (l0 - axis_point).dot(axis);
  s.v_scale = d.dot(axis);
  return true;
}

// A linear extrusion of a line is a plane, of a circle along its axis a cylinder.
bool from_extrusion(const Geom_SurfaceOfLinearExtrusion& ext, AnalyticSurface& s) {
  const Handle(Geom_Curve) basis = unwrap(ext.BasisCurve());
  const Vec3 d = v3(ext.Direction().XYZ());
  if (const auto line = Handle(Geom_Line)::DownCast(basis)) {
    const Vec3 dl = v3(line->Position().Direction().XYZ());
    if (std::abs(dl.dot(d)) > 1e-12) return false;  // (u, v) would not be orthonormal
    s.kind = AnalyticSurface::Kind::kPlane;
    s.origin = v3(line->Position().Location().XYZ());
    s.x = dl;
    s.y = d;
    s.z = dl.cross(d);
    return true;
  }
  if (const auto circle = Handle(Geom_Circle)::DownCast(basis)) {
    if (1.0 - std::abs(v3(circle->Axis().Direction().XYZ()).dot(d)) > kParallel) return false;
    set_frame(s, circle->Position());
    s.kind = AnalyticSurface::Kind::kCylinder;
    s.z = d;
    s.radius = circle->Radius();
    return true;
  }
  return false;
}

}  // namespace

Vec3 AnalyticSurface::point(const Eigen::Vector2d& uv) const {
  if (kind == Kind::kPlane) return origin + uv.x() * x + uv.y() * y;
  return origin + radius * (std::cos(uv.x()) * x + std::sin(uv.x()) * y) +
         (v_offset + v_scale * uv.y()) * z;
}

Vec3 AnalyticSurface::normal(const Eigen::Vector2d& uv) const {
  if (kind == Kind::kPlane) return sense * x.cross(y).normalized();
  const Vec3 pu = radius * (-std::sin(uv.x()) * x + std::cos(uv.x()) * y);
  return sense * pu.cross(v_scale * z).normalized();
}

Eigen::Vector2d AnalyticSurface::project(const Vec3& p, Vec3& foot) const {
  const Vec3 w = p - origin;
  if (kind == Kind::kPlane) {
    const Eigen::Vector2d uv(w.dot(x), w.dot(y));
    foot = origin + uv.x() * x + uv.y() * y;
    return uv;
  }
  const double axial = w.dot(z);
  const Vec3 radial = w - axial * z;
  // On the axis every direction is closest: take u = 0.
  const double u = radial.squaredNorm() > 0.0 ? std::atan2(radial.dot(y), radial.dot(x)) : 0.0;
  const Eigen::Vector2d uv(u, (axial - v_offset) / v_scale);
  foot = point(uv);
  return uv;
}

AnalyticSurface analytic_surface(const TopoDS_Face& face) {
  AnalyticSurface s;
  s.sense = face.Orientation() == TopAbs_REVERSED ? -1.0 : 1.0;
  Handle(Geom_Surface) surface = BRep_Tool::Surface(face);  // location applied
  while (auto trimmed = Handle(Geom_RectangularTrimmedSurface)::DownCast(surface))
    surface = trimmed->BasisSurface();
  if (const auto plane = Handle(Geom_Plane)::DownCast(surface)) {
    set_frame(s, plane->Position());
    s.kind = AnalyticSurface::Kind::kPlane;
  } else if (const auto cylinder = Handle(Geom_CylindricalSurface)::DownCast(surface)) {
    set_frame(s, cylinder->Position());
    s.kind = AnalyticSurface::Kind::kCylinder;
    s.radius = cylinder->Radius();
  } else if (const auto rev = Handle(Geom_SurfaceOfRevolution)::DownCast(surface)) {
    from_revolution(*rev, s);
  } else if (const auto ext = Handle(Geom_SurfaceOfLinearExtrusion)::DownCast(surface)) {
    from_extrusion(*ext, s);
  }
  return s;
}

}  // namespace springscan::analysis
