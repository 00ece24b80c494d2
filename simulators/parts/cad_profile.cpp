// OpenCASCADE shapes of sheet profiles: the reference-side path of profile_path() in the x-z
// plane extruded along +y (sheet_profile.hpp states the conventions).
#include "simulators/parts/cad_profile.hpp"

#include <BRepBuilderAPI_MakeEdge.hxx>
#include <BRepBuilderAPI_MakeFace.hxx>
#include <BRepBuilderAPI_MakeWire.hxx>
#include <BRepBuilderAPI_Transform.hxx>
#include <BRepPrimAPI_MakePrism.hxx>
#include <BRepTools.hxx>
#include <GC_MakeArcOfCircle.hxx>
#include <IGESControl_Controller.hxx>
#include <IGESControl_Writer.hxx>
#include <Interface_Static.hxx>
#include <STEPControl_Writer.hxx>
#include <Standard_Failure.hxx>
#include <algorithm>
#include <cctype>
#include <filesystem>
#include <fstream>
#include <optional>

#include "analysis/cad/internal.hpp"

namespace springscan::parts {
namespace {

gp_Pnt to_occt(const Eigen::Vector2d& xz) { return gp_Pnt(xz.x(), 0.0, xz.y()); }

TopoDS_Edge line_edge(const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  return BRepBuilderAPI_MakeEdge(to_occt(a), to_occt(b));
}

// An arc through start, middle and end: the middle point fixes the side and the sweep.
TopoDS_Edge arc_edge(const ProfileElement& arc, double radius) {
  const double mid_angle = arc.start_angle_rad + 0.5 * arc.sweep_rad;
  const double end_angle = arc.start_angle_rad + arc.sweep_rad;
  const auto on_arc = [&](double angle) {
    return Eigen::Vector2d(arc.center + radius * Eigen::Vector2d(std::cos(angle), std::sin(angle)));
  };
  const Handle(Geom_TrimmedCurve) curve = GC_MakeArcOfCircle(
      to_occt(on_arc(arc.start_angle_rad)), to_occt(on_arc(mid_angle)), to_occt(on_arc(end_angle)));
  return BRepBuilderAPI_MakeEdge(curve);
}

// The path moved `offset` to the right of the direction of travel (the far side of the sheet),
// in reverse order so that it closes the section outline.
void append_offset_side(const std::vector<ProfileElement>& path, double offset,
                        BRepBuilderAPI_MakeWire& wire) {
  for (auto it = path.rbegin(); it != path.rend(); ++it) {
    if (it->kind == ProfileElement::Kind::kLine) {
      const Eigen::Vector2d d = (it->end - it->start).normalized();
      const Eigen::Vector2d right(d.y(), -d.x());
      wire.Add(line_edge(it->end + offset * right, it->start + offset * right));
    } else {
      // Left turns have the centre on the left, so the right side is the outer, larger arc.
      const double radius = it->radius_mm + (it->sweep_rad > 0.0 ? offset : -offset);
      ProfileElement reversed = *it;
      reversed.start_angle_rad = it->start_angle_rad + it->sweep_rad;
      reversed.sweep_rad = -it->sweep_rad;
      wire.Add(arc_edge(reversed, radius));
    }
  }
}

TopoDS_Shape build_profile(const ProfileSpec& spec) {
  const auto path = profile_path(spec);
  BRepBuilderAPI_MakeWire wire;
  for (const auto& element : path) {
    wire.Add(element.kind == ProfileElement::Kind::kLine ? line_edge(element.start, element.end)
                                                         : arc_edge(element, element.radius_mm));
  }
  const gp_Vec extrusion(0.0, spec.width_mm, 0.0);
  if (spec.thickness_mm <= 0.0) return BRepPrimAPI_MakePrism(wire.Wire(), extrusion).Shape();
  const double t = spec.thickness_mm;
  const auto right_of_line = [&](const ProfileElement& line, const Eigen::Vector2d& p) {
    const Eigen::Vector2d d = (line.end - line.start).normalized();
    return Eigen::Vector2d(p + t * Eigen::Vector2d(d.y(), -d.x()));
  };
  wire.Add(line_edge(path.back().end, right_of_line(path.back(), path.back().end)));
  append_offset_side(path, t, wire);
  wire.Add(line_edge(right_of_line(path.front(), path.front().start), path.front().start));
  const TopoDS_Face section = BRepBuilderAPI_MakeFace(wire.Wire(), /*OnlyPlane=*/true);
  return BRepPrimAPI_MakePrism(section, extrusion).Shape();
}

std::string lower_extension(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext;
}

std::optional<double> mm_per_unit(const std::string& unit) {
  if (unit == "MM") return 1.0;
  if (unit == "CM") return 10.0;
  if (unit == "M") return 1000.0;
  if (unit == "INCH") return 25.4;
  if (unit == "FT") return 304.8;
  return std::nullopt;
}

Expected<bool> write_shape(const TopoDS_Shape& shape, const std::string& path,
                           const std::string& unit) {
  const std::string ext = lower_extension(path);
  bool written = false;
  if (ext == ".brep" || ext == ".brp") {
    std::ofstream out(path);
    BRepTools::Write(shape, out, false, false, TopTools_FormatVersion_CURRENT);
    written = out.good();
  } else if (ext == ".igs" || ext == ".iges") {
    const std::lock_guard<std::mutex> lock(occt_exchange_mutex());
    IGESControl_Controller::Init();
    IGESControl_Writer writer(unit.c_str(), /*modecr=faces*/ 0);
    writer.AddShape(shape);
    writer.ComputeModel();
    written = writer.Write(path.c_str());
  } else if (ext == ".stp" || ext == ".step") {
    const std::lock_guard<std::mutex> lock(occt_exchange_mutex());
    // OCCT 7.6's STEP writer declares write.step.unit but does not scale to it: scale here.
    const auto factor = mm_per_unit(unit);
    if (!factor) return fail(path + ": unknown length unit '" + unit + "'");
    gp_Trsf to_unit;
    to_unit.SetScale(gp_Pnt(0, 0, 0), 1.0 / *factor);
    const TopoDS_Shape scaled = BRepBuilderAPI_Transform(shape, to_unit, true).Shape();
    STEPControl_Writer writer;
    Interface_Static::SetCVal("write.step.unit", unit.c_str());
    const bool transferred = writer.Transfer(scaled, STEPControl_AsIs) == IFSelect_RetDone;
    written = transferred && writer.Write(path.c_str()) == IFSelect_RetDone;
    Interface_Static::SetCVal("write.step.unit", "MM");
  } else {
    return fail(path + ": unsupported file type to write (expected .igs, .step or .brep)");
  }
  if (!written) return fail(path + ": could not write the " + ext + " file (unit " + unit + ")");
  return true;
}

}  // namespace

Expected<CadShape> make_profile_shape(const ProfileSpec& spec, const CadImportSettings& settings) {
  if (!is_valid(spec)) return fail("profile spec: invalid (sizes, lengths, radii or angles)");
  try {
    CadLoadReport report;
    report.file = "(profile)";
    report.format = "built";
    return make_cad_shape(build_profile(spec), report, settings);
  } catch (const Standard_Failure& e) {
    return fail(describe_occt_failure("profile spec", e.GetMessageString()));
  }
}

Expected<bool> write_cad(const CadShape& shape, const std::string& path, const std::string& unit) {
  if (shape.empty()) return fail(path + ": nothing to write (empty shape)");
  try {
    return write_shape(shape.impl().shape, path, unit);
  } catch (const Standard_Failure& e) {
    return fail(describe_occt_failure(path, e.GetMessageString()));
  }
}

Expected<bool> write_profile_cad(const ProfileSpec& spec, const std::string& path,
                                 const std::string& unit) {
  if (!is_valid(spec))
    return fail(path + ": invalid profile spec (sizes, lengths, radii or angles)");
  try {
    return write_shape(build_profile(spec), path, unit);
  } catch (const Standard_Failure& e) {
    return fail(describe_occt_failure(path, e.GetMessageString()));
  }
}

}  // namespace springscan::parts
