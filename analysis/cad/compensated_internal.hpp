#pragma once
// PRIVATE to analysis/cad/compensated_*.cpp: the refits of one moved face or edge
// (compensated_fit.cpp), used by the shape modification (compensated_solid.cpp).

#include <Geom2d_Curve.hxx>
#include <Geom_BSplineCurve.hxx>
#include <Geom_Surface.hxx>
#include <TopoDS_Face.hxx>
#include <string>
#include <vector>

#include "analysis/cad/compensated_solid.hpp"

namespace springscan::analysis::compensated {

/// One sample of a face: its (u, v) on the old surface and where it moves to.
struct FaceSample {
  Eigen::Vector2d uv = Eigen::Vector2d::Zero();
  Vec3 moved = Vec3::Zero();
  /// The grid row and column of an inside sample (-1 for a boundary sample): the cylinder fit
  /// reads the axis from the grid's columns.
  int row = -1, column = -1;
  /// How far the sample may lie from a plane or cylinder that replaces the face (mm):
  /// canonical_tolerance_mm + uncertainty_factor x the field's uncertainty there.
  double allowance_mm = 0.0;
};

/// The refit of one face: the new surface and how its trimming curves follow.
struct FaceFit {
  Handle(Geom_Surface) surface;
  std::string kind;  ///< "plane", "cylinder" or "bspline"
  /// true: the surface keeps the old (u, v) (B-spline refit), the old pcurves stay valid;
  /// false: a canonical surface, the pcurves are mapped through uv_of().
  bool same_parameters = true;
  double max_deviation_mm = 0.0;
  double canonical_deviation_mm = -1.0;            ///< of the plane/cylinder tried (-1: none tried)
  Eigen::Vector2d uv_of(const Vec3& moved) const;  ///< canonical surfaces only
  // Canonical frame (plane: origin, x, y; cylinder: axis point, x, y, axis, radius).
  Vec3 origin = Vec3::Zero(), x = Vec3::UnitX(), y = Vec3::UnitY(), z = Vec3::UnitZ();
  double radius = 0.0;
};

/// The refit of `samples` of `face` (old surface `old_surface`, its (u, v) box [u0,u1]x[v0,v1]):
/// a plane or cylinder when the old face is one and the moved samples stay on one within
/// settings.canonical_tolerance_mm (and `may_be_canonical`: no seam), else a B-spline in the
/// old parameters over the box.
FaceFit fit_face(const TopoDS_Face& face, const std::vector<FaceSample>& samples,
                 const Eigen::Vector4d& uv_box, bool may_be_canonical,
                 const CompensatedShapeSettings& settings);

/// A plane through `point` with `normal` (flipped to the side of `old`'s Pu x Pv, so the face
/// keeps its orientation), its x axis along old's: the FaceFit of a face that stays a plane.
FaceFit plane_surface(const gp_Ax3& old, const Vec3& point, Vec3 normal);

/// The planar faces of one flange moved together: one normal for all, one plane per side of
/// the sheet (faces whose old planes coincide). Samples are weighted by 1 / allowance^2, so the
/// well-measured interior decides over a blurred bend line. fits[i] is faces[i]'s plane; false
/// (fits untouched) when a face is not a plane or the samples do not lie within their
/// allowance (within_allowance): a real form defect, the faces are then refitted one by
/// one. `worst` is the largest distance.
bool fit_flange(const std::vector<TopoDS_Face>& faces,
                const std::vector<const std::vector<FaceSample>*>& samples,
                const CompensatedShapeSettings& settings, std::vector<FaceFit>& fits,
                double& worst);

/// At least settings.canonical_share of the samples lie within their allowance and none
/// beyond settings.max_canonical_deviation_mm (residual[i]: sample i's distance from the plane
/// or cylinder).
bool within_allowance(const std::vector<FaceSample>& samples, const std::vector<double>& residual,
                      const CompensatedShapeSettings& settings);

/// q put on every plane or cylinder of `fits` at once (alternating projections): a moved edge
/// sample onto where its canonical faces meet, a vertex onto their common point. Unchanged
/// when `fits` is empty.
Vec3 onto_surfaces(const std::vector<const FaceFit*>& fits, Vec3 q);

/// A B-spline curve through `points` at `parameters` (ascending); its largest distance from
/// them in `max_deviation_mm`.
Handle(Geom_BSplineCurve) fit_curve(const std::vector<double>& parameters,
                                    const std::vector<Vec3>& points, double& max_deviation_mm);

/// A 2-D B-spline curve through `uv` at `parameters`.
Handle(Geom2d_Curve)
    fit_curve_2d(const std::vector<double>& parameters, const std::vector<Eigen::Vector2d>& uv);

}  // namespace springscan::analysis::compensated
