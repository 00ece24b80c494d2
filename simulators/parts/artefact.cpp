// The calibration artefact built with OpenCASCADE: two boxes fused, then cut by half-spaces.
#include "simulators/parts/artefact.hpp"

#include <BRepAlgoAPI_Cut.hxx>
#include <BRepAlgoAPI_Fuse.hxx>
#include <BRepBuilderAPI_MakeFace.hxx>
#include <BRepPrimAPI_MakeBox.hxx>
#include <BRepPrimAPI_MakeHalfSpace.hxx>
#include <ShapeUpgrade_UnifySameDomain.hxx>
#include <Standard_Failure.hxx>
#include <gp_Pln.hxx>

#include "analysis/cad/internal.hpp"
#include "simulators/parts/cad_profile.hpp"

namespace springscan::parts {
namespace {

using analysis::Vec3;

/// Removes what lies on the `normal` side of the plane through `point`.
TopoDS_Shape cut_above(const TopoDS_Shape& body, const Vec3& point, const Vec3& normal) {
  const Vec3 n = normal.normalized();
  const gp_Pln plane(gp_Pnt(point.x(), point.y(), point.z()), gp_Dir(n.x(), n.y(), n.z()));
  const TopoDS_Face face = BRepBuilderAPI_MakeFace(plane).Face();
  const Vec3 outside = point + 10.0 * n;
  const TopoDS_Solid half =
      BRepPrimAPI_MakeHalfSpace(face, gp_Pnt(outside.x(), outside.y(), outside.z())).Solid();
  BRepAlgoAPI_Cut cut(body, half);
  cut.Build();
  if (!cut.IsDone()) throw Standard_Failure("artefact: a planar cut failed");
  return cut.Shape();
}

TopoDS_Shape build_artefact(const ArtefactSpec& s) {
  const double L = s.length_mm, W = s.width_mm, H = s.base_height_mm, S = s.step_height_mm;
  const TopoDS_Shape base = BRepPrimAPI_MakeBox(gp_Pnt(0, 0, 0), gp_Pnt(L, W, H)).Shape();
  // The step sits off centre, towards -x and +y: no symmetry of the box survives.
  const TopoDS_Shape step =
      BRepPrimAPI_MakeBox(gp_Pnt(0.125 * L, 0.5 * W, H), gp_Pnt(0.5 * L, 0.95 * W, H + S)).Shape();
  TopoDS_Shape body = BRepAlgoAPI_Fuse(base, step).Shape();
  const double c = s.chamfer_mm;
  // 45-degree chamfers on the base's +x and -y top edges: normals (1, 0, 1) and (0, -1, 1).
  body = cut_above(body, Vec3(L - c, 0, H), Vec3(1, 0, 1));
  body = cut_above(body, Vec3(0, c, H), Vec3(0, -1, 1));
  // The step's far corner cut on a diagonal (-1, 1, 1.2), and a 27-degree ramp down to -x on
  // its top (-1, 0, 2): normals in four azimuths, at three slopes.
  body = cut_above(body, Vec3(0.2 * L, 0.95 * W - 0.15 * W, H + S), Vec3(-1, 1, 1.2));
  body = cut_above(body, Vec3(0.25 * L, 0.7 * W, H + S), Vec3(-1, 0, 2));
  ShapeUpgrade_UnifySameDomain unify(body, true, true, false);
  unify.Build();
  return unify.Shape();
}

bool valid(const ArtefactSpec& s) {
  return s.length_mm > 0 && s.width_mm > 0 && s.base_height_mm > 0 && s.step_height_mm > 0 &&
         s.chamfer_mm > 0 && s.chamfer_mm < s.base_height_mm && s.chamfer_mm < 0.5 * s.length_mm &&
         s.chamfer_mm < 0.4 * s.width_mm;
}

}  // namespace

analysis::Expected<analysis::CadShape> make_artefact_shape(
    const ArtefactSpec& spec, const analysis::CadImportSettings& settings) {
  if (!valid(spec)) return analysis::fail("artefact spec: sizes must be positive and consistent");
  try {
    analysis::CadLoadReport report;
    report.file = "(calibration artefact)";
    report.format = "built";
    return analysis::make_cad_shape(build_artefact(spec), report, settings);
  } catch (const Standard_Failure& e) {
    return analysis::fail(std::string("artefact: ") + e.GetMessageString());
  }
}

analysis::Expected<bool> write_artefact_step(const std::string& path, const ArtefactSpec& spec) {
  auto shape = make_artefact_shape(spec);
  if (!shape) return shape.error();
  return write_cad(*shape, path, "MM");
}

}  // namespace springscan::parts
