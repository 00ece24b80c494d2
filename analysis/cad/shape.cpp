// CadShape: counting, measuring and tessellating an OpenCASCADE shape into our types.
#include <BRepBndLib.hxx>
#include <BRepGProp.hxx>
#include <BRepMesh_IncrementalMesh.hxx>
#include <BRep_Tool.hxx>
#include <Bnd_Box.hxx>
#include <GProp_GProps.hxx>
#include <Poly_Triangulation.hxx>
#include <Standard_Failure.hxx>
#include <TopExp.hxx>
#include <TopTools_IndexedDataMapOfShapeListOfShape.hxx>
#include <TopTools_ListOfShape.hxx>
#include <TopoDS.hxx>
#include <cmath>
#include <numbers>
#include <sstream>

#include "analysis/cad/internal.hpp"

namespace springscan::analysis {
namespace {

int count_free_edges(const TopoDS_Shape& shape) {
  TopTools_IndexedDataMapOfShapeListOfShape edge_faces;
  TopExp::MapShapesAndAncestors(shape, TopAbs_EDGE, TopAbs_FACE, edge_faces);
  int free_edges = 0;
  for (int i = 1; i <= edge_faces.Extent(); ++i) {
    const TopoDS_Edge& edge = TopoDS::Edge(edge_faces.FindKey(i));
    if (BRep_Tool::Degenerated(edge)) continue;
    const TopTools_ListOfShape& faces = edge_faces(i);
    if (faces.IsEmpty()) continue;
    const TopoDS_Shape& first = faces.First();
    bool shared = false;
    for (const TopoDS_Shape& face : faces) shared = shared || !face.IsSame(first);
    // A seam edge (a cylinder's closing edge) bounds the same face twice: not free.
    if (!shared && !BRep_Tool::IsClosed(edge, TopoDS::Face(first))) ++free_edges;
  }
  return free_edges;
}

void measure(const TopoDS_Shape& shape, CadLoadReport& report) {
  TopTools_IndexedMapOfShape map;
  TopExp::MapShapes(shape, TopAbs_SHELL, map);
  report.shells = map.Extent();
  map.Clear();
  TopExp::MapShapes(shape, TopAbs_SOLID, map);
  report.solids = map.Extent();
  report.free_edges = count_free_edges(shape);
  GProp_GProps props;
  BRepGProp::SurfaceProperties(shape, props);
  report.area_mm2 = props.Mass();
  Bnd_Box box;
  BRepBndLib::Add(shape, box);
  if (!box.IsVoid()) {
    double x0, y0, z0, x1, y1, z1;
    box.Get(x0, y0, z0, x1, y1, z1);
    report.bbox_min = Vec3(x0, y0, z0);
    report.bbox_max = Vec3(x1, y1, z1);
  }
}

// Appends one face's triangulation: nodes mapped by the face location, winding flipped for
// REVERSED faces so every triangle's normal points along the face's outward normal.
void append_face_mesh(const TopoDS_Face& face, int face_id, CadMesh& mesh) {
  TopLoc_Location location;
  const Handle(Poly_Triangulation) tri = BRep_Tool::Triangulation(face, location);
  if (tri.IsNull() || tri->NbTriangles() == 0) return;
  const gp_Trsf& trsf = location.Transformation();
  const auto base = static_cast<std::uint32_t>(mesh.vertices.size());
  for (int i = 1; i <= tri->NbNodes(); ++i) {
    const gp_Pnt p = tri->Node(i).Transformed(trsf);
    mesh.vertices.emplace_back(p.X(), p.Y(), p.Z());
    const gp_Pnt2d uv = tri->HasUVNodes() ? tri->UVNode(i) : gp_Pnt2d(0, 0);
    mesh.uv.emplace_back(uv.X(), uv.Y());
  }
  const bool reversed = face.Orientation() == TopAbs_REVERSED;
  for (int i = 1; i <= tri->NbTriangles(); ++i) {
    int a, b, c;
    tri->Triangle(i).Get(a, b, c);
    if (reversed) std::swap(b, c);
    mesh.triangles.push_back({base + static_cast<std::uint32_t>(a - 1),
                              base + static_cast<std::uint32_t>(b - 1),
                              base + static_cast<std::uint32_t>(c - 1)});
    mesh.triangle_faces.push_back(face_id);
  }
  mesh.face_deflection_mm[static_cast<std::size_t>(face_id)] = tri->Deflection();
}

}  // namespace

int CadShape::face_count() const { return impl_ ? impl_->faces.Extent() : 0; }
const CadLoadReport& CadShape::report() const { return impl_->report; }
const CadMesh& CadShape::mesh() const { return impl_->mesh; }

Expected<CadShape> make_cad_shape(const TopoDS_Shape& shape, CadLoadReport report,
                                  const CadImportSettings& settings) {
  if (!(settings.linear_deflection_mm > 0.0) || !(settings.angular_deflection_deg > 0.0)) {
    std::ostringstream message;
    message << report.file << ": deflections must be positive (linear "
            << settings.linear_deflection_mm << " mm, angular " << settings.angular_deflection_deg
            << " deg)";
    return fail(message.str());
  }
  try {
    auto impl = std::make_shared<CadShape::Impl>();
    impl->shape = shape;
    TopExp::MapShapes(shape, TopAbs_FACE, impl->faces);
    report.faces = impl->faces.Extent();
    if (report.faces == 0) return fail(report.file + ": the shape holds no faces");
    measure(shape, report);
    // BRepMesh: chord tolerance in mm, angle in radians, serial (the thread count is ours).
    BRepMesh_IncrementalMesh mesher(shape, settings.linear_deflection_mm, false,
                                    settings.angular_deflection_deg * std::numbers::pi / 180.0,
                                    false);
    impl->mesh.face_deflection_mm.assign(static_cast<std::size_t>(report.faces), 0.0);
    for (int id = 0; id < report.faces; ++id) {
      const auto before = impl->mesh.triangles.size();
      append_face_mesh(impl->face(id), id, impl->mesh);
      if (impl->mesh.triangles.size() == before) ++report.faces_without_mesh;
    }
    report.triangles = static_cast<int>(impl->mesh.triangles.size());
    prepare_trimming(*impl, settings.linear_deflection_mm);
    impl->report = report;
    return CadShape(std::move(impl));
  } catch (const Standard_Failure& e) {
    return fail(describe_occt_failure(report.file, e.GetMessageString()));
  }
}

std::string summary(const CadLoadReport& r) {
  std::ostringstream out;
  const Vec3 size = r.bbox_max - r.bbox_min;
  out << r.format << ": faces " << r.faces << ", shells " << r.shells << ", solids " << r.solids
      << ", free edges " << r.free_edges << ", area " << r.area_mm2 << " mm2, bbox " << size.x()
      << " x " << size.y() << " x " << size.z() << " mm, triangles " << r.triangles;
  if (r.sewn) out << ", sewn";
  if (r.healed) out << ", healed";
  if (r.scale_applied != 1.0) out << ", scaled x" << r.scale_applied << " (metre-scale rule)";
  if (r.faces_without_mesh > 0) out << ", " << r.faces_without_mesh << " faces without mesh";
  return out.str();
}

}  // namespace springscan::analysis
