// IGES / STEP / BRep import: read, convert to mm, sew, heal. The shape is then counted
// and tessellated by make_cad_shape (cad_shape.cpp).
#include <BRepBndLib.hxx>
#include <BRepBuilderAPI_Sewing.hxx>
#include <BRepBuilderAPI_Transform.hxx>
#include <BRepTools.hxx>
#include <BRep_Builder.hxx>
#include <Bnd_Box.hxx>
#include <IFSelect_ReturnStatus.hxx>
#include <IGESControl_Reader.hxx>
#include <Interface_Static.hxx>
#include <Message.hxx>
#include <Message_Messenger.hxx>
#include <Message_PrinterOStream.hxx>
#include <STEPControl_Reader.hxx>
#include <ShapeAnalysis_FreeBounds.hxx>
#include <ShapeFix_Shape.hxx>
#include <ShapeFix_Solid.hxx>
#include <Standard_Failure.hxx>
#include <TopExp.hxx>
#include <TopExp_Explorer.hxx>
#include <TopTools_IndexedMapOfShape.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Solid.hxx>
#include <algorithm>
#include <cctype>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "analysis/cad/internal.hpp"

namespace springscan::analysis {
namespace {

enum class Format { kIges, kStep, kBrep, kUnknown };

Format format_of(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (ext == ".igs" || ext == ".iges") return Format::kIges;
  if (ext == ".stp" || ext == ".step") return Format::kStep;
  if (ext == ".brep" || ext == ".brp") return Format::kBrep;
  return Format::kUnknown;
}

const char* format_name(Format format) {
  switch (format) {
    case Format::kIges:
      return "IGES";
    case Format::kStep:
      return "STEP";
    case Format::kBrep:
      return "BREP";
    case Format::kUnknown:
      break;
  }
  return "unknown";
}

// Reads IGES or STEP with the target unit set to mm: the readers scale from the unit the file
// declares (IGES global section fields 14/15, STEP SI_UNIT) to "xstep.cascade.unit"
// (OCCT 7.6 has no read.*.unit parameter).
template <typename Reader>
Expected<TopoDS_Shape> read_exchange(const std::string& path, const char* format) {
  const std::lock_guard<std::mutex> lock(occt_exchange_mutex());
  Reader reader;  // the constructor registers the format's static parameters
  Interface_Static::SetCVal("xstep.cascade.unit", "MM");
  if (reader.ReadFile(path.c_str()) != IFSelect_RetDone)
    return fail(ErrorCode::kCorruption,
                path + ": the file could not be parsed (not valid " + format + ")");
  if (reader.TransferRoots() == 0)
    return fail(ErrorCode::kCorruption, path + ": no shape could be transferred");
  return reader.OneShape();
}

Expected<TopoDS_Shape> read_brep(const std::string& path) {
  std::ifstream in(path);
  TopoDS_Shape shape;
  BRep_Builder builder;
  BRepTools::Read(shape, in, builder);
  if (shape.IsNull())
    return fail(ErrorCode::kCorruption, path + ": the file could not be parsed (not valid BRep)");
  return shape;
}

bool has_loose_faces(const TopoDS_Shape& shape) {
  return TopExp_Explorer(shape, TopAbs_FACE, TopAbs_SHELL).More();
}

double bbox_diagonal(const TopoDS_Shape& shape) {
  Bnd_Box box;
  BRepBndLib::Add(shape, box);
  if (box.IsVoid()) return 0.0;
  return std::sqrt(box.SquareExtent());
}

// A sewn shell without free edges bounds a volume: made a solid (outward oriented by
// ShapeFix_Solid), so that sheet parts from IGES are segmented like the same part from STEP.
TopoDS_Shape close_into_solids(const TopoDS_Shape& shape) {
  TopTools_IndexedMapOfShape shells;
  TopExp::MapShapes(shape, TopAbs_SHELL, shells);
  if (shells.Extent() != 1 || TopExp_Explorer(shape, TopAbs_SOLID).More()) return shape;
  const TopoDS_Shell& shell = TopoDS::Shell(shells(1));
  ShapeAnalysis_FreeBounds bounds(shell);
  if (!bounds.GetClosedWires().IsNull() &&
      TopExp_Explorer(bounds.GetClosedWires(), TopAbs_EDGE).More())
    return shape;
  if (!bounds.GetOpenWires().IsNull() && TopExp_Explorer(bounds.GetOpenWires(), TopAbs_EDGE).More())
    return shape;
  ShapeFix_Solid fix;
  const TopoDS_Solid solid = fix.SolidFromShell(shell);
  return solid.IsNull() ? shape : TopoDS_Shape(solid);
}

// Sewing and healing: loose faces (IGES trimmed surfaces) become shells; ShapeFix_Shape repairs
// wires, tolerances and orientations so that adjacency and sampling see a consistent shape.
TopoDS_Shape sew_and_heal(TopoDS_Shape shape, const CadImportSettings& settings,
                          CadLoadReport& report) {
  if (settings.sew_loose_faces && has_loose_faces(shape)) {
    BRepBuilderAPI_Sewing sewing(settings.sewing_tolerance_mm);
    sewing.Add(shape);
    sewing.Perform();
    if (!sewing.SewedShape().IsNull()) {
      shape = sewing.SewedShape();
      report.sewn = true;
    }
  }
  if (report.sewn) shape = close_into_solids(shape);
  if (settings.heal) {
    ShapeFix_Shape fix(shape);
    fix.SetPrecision(settings.sewing_tolerance_mm * 0.1);
    fix.Perform();
    shape = fix.Shape();
    report.healed = true;
  }
  return shape;
}

// The metre-scale rule of CadImportSettings::min_plausible_size_mm.
TopoDS_Shape apply_plausible_scale(const TopoDS_Shape& shape, const CadImportSettings& settings,
                                   CadLoadReport& report) {
  const double diagonal = bbox_diagonal(shape);
  if (!(diagonal > 0.0) || diagonal >= settings.min_plausible_size_mm) return shape;
  gp_Trsf scale;
  scale.SetScale(gp_Pnt(0, 0, 0), 1000.0);
  report.scale_applied = 1000.0;
  return BRepBuilderAPI_Transform(shape, scale, /*copy=*/true).Shape();
}

Expected<TopoDS_Shape> read_any(const std::string& path, Format format) {
  switch (format) {
    case Format::kIges:
      return read_exchange<IGESControl_Reader>(path, "IGES");
    case Format::kStep:
      return read_exchange<STEPControl_Reader>(path, "STEP");
    case Format::kBrep:
      return read_brep(path);
    case Format::kUnknown:
      break;
  }
  return fail(path + ": unsupported file type (expected .igs, .iges, .stp, .step or .brep)");
}

}  // namespace

std::mutex& occt_exchange_mutex() {
  // Library code never prints (STYLE.md section 5): the data-exchange readers and writers report
  // to OpenCASCADE's default messenger, whose stdout printer is removed once here.
  static std::mutex mutex;
  static const bool silenced = [] {
    Message::DefaultMessenger()->RemovePrinters(STANDARD_TYPE(Message_PrinterOStream));
    return true;
  }();
  (void)silenced;
  return mutex;
}

std::string describe_occt_failure(const std::string& what, const char* message) {
  return what + ": OpenCASCADE failed: " + (message && *message ? message : "(no message)");
}

Expected<CadShape> load_cad(const std::string& path, const CadImportSettings& settings) {
  const Format format = format_of(path);
  if (format == Format::kUnknown)
    return fail(path + ": unsupported file type (expected .igs, .iges, .stp, .step or .brep)");
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec))
    return fail(ErrorCode::kNotFound, path + ": no such file");
  if (std::filesystem::file_size(path, ec) == 0)
    return fail(ErrorCode::kCorruption, path + ": the file is empty");
  if (!std::ifstream(path).good())
    return fail(ErrorCode::kIoError, path + ": cannot open the file for reading");
  CadLoadReport report;
  report.file = path;
  report.format = format_name(format);
  try {
    auto read = read_any(path, format);
    if (!read) return read.error();
    if (read->IsNull() || !TopExp_Explorer(*read, TopAbs_FACE).More())
      return fail(ErrorCode::kCorruption, path + ": the file holds no faces");
    TopoDS_Shape shape = sew_and_heal(*read, settings, report);
    shape = apply_plausible_scale(shape, settings, report);
    return make_cad_shape(shape, report, settings);
  } catch (const Standard_Failure& e) {
    return fail(ErrorCode::kCorruption, describe_occt_failure(path, e.GetMessageString()));
  } catch (const std::exception& e) {
    return fail(path + ": " + e.what());
  }
}

std::string cad_to_brep_text(const CadShape& shape) {
  if (shape.empty()) return {};
  std::ostringstream out;
  BRepTools::Write(shape.impl().shape, out, /*theWithTriangles=*/false,
                   /*theWithNormals=*/false, TopTools_FormatVersion_CURRENT);
  return out.str();
}

Expected<CadShape> cad_from_brep_text(const std::string& text, const std::string& name,
                                      const CadImportSettings& settings) {
  try {
    std::istringstream in(text);
    TopoDS_Shape shape;
    BRep_Builder builder;
    BRepTools::Read(shape, in, builder);
    if (shape.IsNull() || !TopExp_Explorer(shape, TopAbs_FACE).More())
      return fail(ErrorCode::kCorruption, name + ": the BRep text holds no faces");
    CadLoadReport report;
    report.file = name;
    report.format = "BREP";
    return make_cad_shape(shape, report, settings);
  } catch (const Standard_Failure& e) {
    return fail(ErrorCode::kCorruption, describe_occt_failure(name, e.GetMessageString()));
  }
}

}  // namespace springscan::analysis
