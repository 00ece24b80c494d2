// Profiles with holes and slots cut through (sheet_cutouts.hpp).
#include "simulators/parts/sheet_cutouts.hpp"

#include <BRepAlgoAPI_Cut.hxx>
#include <BRepAlgoAPI_Fuse.hxx>
#include <BRepPrimAPI_MakeBox.hxx>
#include <BRepPrimAPI_MakeCylinder.hxx>
#include <Standard_Failure.hxx>
#include <gp_Ax2.hxx>

#include "analysis/cad/internal.hpp"
#include "simulators/parts/cad_profile.hpp"

namespace springscan::parts {
namespace {

constexpr double kReachMm = 50.0;  // the cutting tool's half length along the axis

gp_Pnt pnt(const Vec3& v) { return gp_Pnt(v.x(), v.y(), v.z()); }
gp_Dir dir(const Vec3& v) { return gp_Dir(v.x(), v.y(), v.z()); }

TopoDS_Shape cylinder(const Vec3& centre, const Vec3& axis, double radius) {
  return BRepPrimAPI_MakeCylinder(gp_Ax2(pnt(centre - kReachMm * axis), dir(axis)), radius,
                                  2.0 * kReachMm)
      .Shape();
}

// A round hole's cylinder, or a slot's stadium: a box between its two end cylinders.
TopoDS_Shape tool(const Cutout& c) {
  const double r = 0.5 * c.diameter_mm;
  if (!(c.length_mm > c.diameter_mm)) return cylinder(c.centre, c.axis, r);
  const double half = 0.5 * (c.length_mm - c.diameter_mm);
  const Vec3 across = c.axis.cross(c.along);
  const Vec3 corner = c.centre - half * c.along - r * across - kReachMm * c.axis;
  const gp_Ax2 frame(pnt(corner), dir(c.axis), dir(c.along));
  TopoDS_Shape box = BRepPrimAPI_MakeBox(frame, 2.0 * half, 2.0 * r, 2.0 * kReachMm).Shape();
  box = BRepAlgoAPI_Fuse(box, cylinder(c.centre - half * c.along, c.axis, r)).Shape();
  return BRepAlgoAPI_Fuse(box, cylinder(c.centre + half * c.along, c.axis, r)).Shape();
}

}  // namespace

Expected<CadShape> make_profile_with_cutouts(const ProfileSpec& spec,
                                             const std::vector<Cutout>& cutouts,
                                             const CadImportSettings& settings) {
  if (!(spec.thickness_mm > 0.0)) return fail("profile with cutouts: needs a thickness");
  auto base = make_profile_shape(spec, settings);
  if (!base) return base.error();
  try {
    TopoDS_Shape shape = base->impl().shape;
    for (const Cutout& c : cutouts) {
      BRepAlgoAPI_Cut cut(shape, tool(c));
      if (!cut.IsDone()) return fail("profile with cutouts: a cut failed");
      shape = cut.Shape();
    }
    CadLoadReport report;
    report.file = "(profile with cutouts)";
    report.format = "built";
    return make_cad_shape(shape, report, settings);
  } catch (const Standard_Failure& e) {
    return fail(describe_occt_failure("profile with cutouts", e.GetMessageString()));
  }
}

}  // namespace springscan::parts
