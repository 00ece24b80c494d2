// The compensated die surface (compensated_solid.hpp): sample every face, edge and vertex, move
// the samples by the field, refit (compensated_fit.cpp) and rebuild the shape with the same
// topology through BRepTools_Modifier.
#include "analysis/cad/compensated_solid.hpp"

#include <BRepAdaptor_Curve.hxx>
#include <BRepAdaptor_Surface.hxx>
#include <BRepCheck_Analyzer.hxx>
#include <BRepLib.hxx>
#include <BRepTools.hxx>
#include <BRepTools_Modification.hxx>
#include <BRepTools_Modifier.hxx>
#include <BRepTopAdaptor_FClass2d.hxx>
#include <BRep_Tool.hxx>
#include <Standard_Failure.hxx>
#include <TopExp.hxx>
#include <TopExp_Explorer.hxx>
#include <TopTools_IndexedDataMapOfShapeListOfShape.hxx>
#include <TopTools_ListIteratorOfListOfShape.hxx>
#include <algorithm>
#include <cmath>
#include <cstdio>

#include "analysis/cad/compensated_internal.hpp"
#include "analysis/cad/internal.hpp"
#include "analysis/cad/segmentation.hpp"
#include "analysis/core/kdtree.hpp"

namespace springscan::analysis {
namespace {

using compensated::FaceFit;
using compensated::FaceSample;

Vec3 v3(const gp_XYZ& p) { return {p.X(), p.Y(), p.Z()}; }

struct EdgeData {
  bool moved = false;        // has a 3-D curve (not degenerated)
  std::vector<double> t;     // sample parameters on the 3-D curve
  std::vector<int> index;    // the samples' indices into the point batch
  std::vector<Vec3> points;  // moved samples
  Handle(Geom_BSplineCurve) curve;
  double deviation = 0.0;
};

struct FaceData {
  std::vector<FaceSample> samples;  // inside grid samples, then boundary samples
  std::vector<int> index;           // inside samples' indices into the point batch
  Eigen::Vector4d box = Eigen::Vector4d::Zero();
  bool seam = false;          // an edge bounds the face twice (a closed surface): never canonical
  double boundary_gap = 0.0;  // how far its boundary samples lie from the refit
  FaceFit fit;
  CompensatedFace report;
};

// Everything sampled, then moved: the point batch the field is asked about once.
struct Sampling {
  TopTools_IndexedMapOfShape vertices, edges;
  std::vector<Vec3> points;
  std::vector<EdgeData> edge;
  std::vector<FaceData> face;
  std::vector<Vec3> offset;  // per point, after filling the uncovered ones
  std::vector<bool> covered;
  std::vector<double> uncertainty;  // the field's, per point (mm)
  std::vector<Vec3> vertex_points;  // where each vertex goes
  int add(const gp_Pnt& p) {
    points.emplace_back(p.X(), p.Y(), p.Z());
    return static_cast<int>(points.size()) - 1;
  }
};

void sample_edges(Sampling& s, const CompensatedShapeSettings& settings) {
  s.edge.resize(static_cast<std::size_t>(s.edges.Extent()));
  const int n = std::max(settings.edge_samples, 8);
  for (int i = 1; i <= s.edges.Extent(); ++i) {
    const TopoDS_Edge& e = TopoDS::Edge(s.edges(i));
    EdgeData& d = s.edge[static_cast<std::size_t>(i - 1)];
    if (BRep_Tool::Degenerated(e) || !BRep_Tool::IsGeometric(e)) continue;
    const BRepAdaptor_Curve curve(e);
    d.moved = true;
    for (int k = 0; k < n; ++k) {
      const double t =
          curve.FirstParameter() + (curve.LastParameter() - curve.FirstParameter()) * k / (n - 1);
      d.t.push_back(t);
      d.index.push_back(s.add(curve.Value(t)));
    }
  }
}

// The face's grid samples inside its trimming, over its (u, v) box.
void sample_face(const TopoDS_Face& face, FaceData& d, Sampling& s,
                 const CompensatedShapeSettings& settings) {
  double u0, u1, v0, v1;
  BRepTools::UVBounds(face, u0, u1, v0, v1);
  d.box << u0, u1, v0, v1;
  const BRepAdaptor_Surface surface(face);
  const BRepTopAdaptor_FClass2d classifier(face, 1e-7);
  const int n = std::max(settings.face_samples, 4);
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) {
      const double u = u0 + (u1 - u0) * i / (n - 1), v = v0 + (v1 - v0) * j / (n - 1);
      const TopAbs_State state = classifier.Perform(gp_Pnt2d(u, v));
      if (state != TopAbs_IN && state != TopAbs_ON) continue;
      FaceSample sample;
      sample.uv = {u, v};
      sample.row = j;
      sample.column = i;
      d.samples.push_back(sample);
      d.index.push_back(s.add(surface.Value(u, v)));
    }
  }
  for (TopExp_Explorer x(face, TopAbs_EDGE); x.More(); x.Next())
    d.seam = d.seam || BRep_Tool::IsClosed(TopoDS::Edge(x.Current()), face);
}

// The field at every sample; an uncovered sample takes its nearest covered sample's offset.
Expected<bool> ask_field(Sampling& s, const OffsetField& field) {
  PointOffsets answer = field(s.points);
  if (answer.uncertainty_mm.empty()) answer.uncertainty_mm.assign(s.points.size(), 0.0);
  if (answer.offset.size() != s.points.size() || answer.covered.size() != s.points.size() ||
      answer.uncertainty_mm.size() != s.points.size())
    return fail(ErrorCode::kInternal, "compensated shape: the field answered " +
                                          std::to_string(answer.offset.size()) + " offsets for " +
                                          std::to_string(s.points.size()) + " points");
  std::vector<Vec3> anchors;
  std::vector<std::size_t> anchor_index;
  for (std::size_t i = 0; i < s.points.size(); ++i) {
    if (!answer.covered[i]) continue;
    if (!answer.offset[i].allFinite() || !std::isfinite(answer.uncertainty_mm[i]))
      return fail("compensated shape: the field is not finite at a sample");
    anchors.push_back(s.points[i]);
    anchor_index.push_back(i);
  }
  if (anchors.empty()) return fail("compensated shape: the field covers no point of the CAD");
  const KdTree tree(anchors);
  for (std::size_t i = 0; i < s.points.size(); ++i) {
    if (answer.covered[i]) continue;
    const auto nearest = tree.nearest(s.points[i]);
    answer.offset[i] = answer.offset[anchor_index[nearest->index]];
    answer.uncertainty_mm[i] = answer.uncertainty_mm[anchor_index[nearest->index]];
  }
  s.uncertainty = std::move(answer.uncertainty_mm);
  s.offset = std::move(answer.offset);
  s.covered = std::move(answer.covered);
  return true;
}

std::string describe(const CadFaceInfo& f) {
  char text[160];
  std::snprintf(text, sizeof text, "face %d (%s, %.1f mm2, centroid %.2f %.2f %.2f)", f.id,
                f.type.c_str(), f.area_mm2, f.centroid.x(), f.centroid.y(), f.centroid.z());
  return text;
}

// How far a moved sample may lie from a plane or cylinder (compensated_solid.hpp).
double allowance(const Sampling& s, int point, const CompensatedShapeSettings& settings) {
  return settings.canonical_tolerance_mm +
         settings.uncertainty_factor * s.uncertainty[static_cast<std::size_t>(point)];
}

// The face's boundary samples: every edge's moved samples at the edge's pcurve on the face.
void add_boundary(const TopoDS_Face& face, FaceData& d, const Sampling& s,
                  const CompensatedShapeSettings& settings) {
  for (TopExp_Explorer x(face, TopAbs_EDGE); x.More(); x.Next()) {
    const TopoDS_Edge& e = TopoDS::Edge(x.Current());
    const EdgeData& edge = s.edge[static_cast<std::size_t>(s.edges.FindIndex(e) - 1)];
    if (!edge.moved) continue;
    double f, l;
    const Handle(Geom2d_Curve) pcurve = BRep_Tool::CurveOnSurface(e, face, f, l);
    if (pcurve.IsNull()) continue;
    const double t0 = edge.t.front(), t1 = edge.t.back();
    for (std::size_t k = 0; k < edge.t.size(); ++k) {
      // Same-parameter edges share the range; map it anyway should a pcurve's range differ.
      const double t = f + (l - f) * (edge.t[k] - t0) / (t1 - t0);
      const gp_Pnt2d uv = pcurve->Value(t);
      FaceSample sample;
      sample.uv = {uv.X(), uv.Y()};
      sample.moved = edge.points[k];
      sample.allowance_mm = allowance(s, edge.index[k], settings);
      d.samples.push_back(sample);
    }
  }
}

// How far the refit lies from each moved sample: at the sample's own (u, v) for a B-spline in the
// old parameters, at its projection for a plane or cylinder.
void face_deviations(FaceData& d, std::vector<double>& all) {
  for (const FaceSample& s : d.samples) {
    const Eigen::Vector2d uv = d.fit.same_parameters ? s.uv : d.fit.uv_of(s.moved);
    const double e = (v3(d.fit.surface->Value(uv.x(), uv.y()).XYZ()) - s.moved).norm();
    d.report.max_deviation_mm = std::max(d.report.max_deviation_mm, e);
    if (s.row < 0) d.boundary_gap = std::max(d.boundary_gap, e);
    all.push_back(e);
  }
}

// The new geometry of every face, edge and vertex, handed to BRepTools_Modifier, which rebuilds
// the shape around it with the same topology.
class FieldModification : public BRepTools_Modification {
 public:
  /// loose: every face's tolerance covers its samples' scatter (see rebuild).
  FieldModification(const Sampling& s, const TopTools_IndexedMapOfShape& faces,
                    std::vector<Vec3> vertex_points, bool loose)
      : s_(s), faces_(faces), vertex_points_(std::move(vertex_points)), loose_(loose) {}

  Standard_Boolean NewSurface(const TopoDS_Face& f, Handle(Geom_Surface) & surface,
                              TopLoc_Location& location, Standard_Real& tolerance,
                              Standard_Boolean& reverse_wires,
                              Standard_Boolean& reverse_face) override {
    const FaceData& d = face(f);
    surface = d.fit.surface;
    location = TopLoc_Location();
    // A plane or cylinder meets its edges (project_onto_canonical): its tolerance stays, the
    // scatter it leaves out is no gap; a B-spline only follows its boundary that closely.
    tolerance =
        std::max(BRep_Tool::Tolerance(f),
                 d.fit.same_parameters || loose_ ? d.report.max_deviation_mm : d.boundary_gap);
    reverse_wires = reverse_face = Standard_False;
    return Standard_True;
  }
  Standard_Boolean NewCurve(const TopoDS_Edge& e, Handle(Geom_Curve) & curve,
                            TopLoc_Location& location, Standard_Real& tolerance) override {
    const EdgeData& d = edge(e);
    if (!d.moved) return Standard_False;
    curve = d.curve;
    location = TopLoc_Location();
    tolerance = std::max(BRep_Tool::Tolerance(e), d.deviation);
    return Standard_True;
  }
  Standard_Boolean NewPoint(const TopoDS_Vertex& v, gp_Pnt& point,
                            Standard_Real& tolerance) override {
    const Vec3& p = vertex_points_[static_cast<std::size_t>(s_.vertices.FindIndex(v) - 1)];
    point.SetCoord(p.x(), p.y(), p.z());
    tolerance = BRep_Tool::Tolerance(v);
    return Standard_True;
  }
  Standard_Boolean NewCurve2d(const TopoDS_Edge& e, const TopoDS_Face& f, const TopoDS_Edge&,
                              const TopoDS_Face&, Handle(Geom2d_Curve) & curve,
                              Standard_Real& tolerance) override {
    const FaceData& d = face(f);
    const EdgeData& ed = edge(e);
    double first, last;
    const Handle(Geom2d_Curve) old = BRep_Tool::CurveOnSurface(e, f, first, last);
    if (old.IsNull()) return Standard_False;
    tolerance = BRep_Tool::Tolerance(e);
    if (d.fit.same_parameters || !ed.moved) {
      curve = Handle(Geom2d_Curve)::DownCast(old->Copy());
      return Standard_True;
    }
    // A plane or cylinder in new parameters: the trimming curve follows the moved edge.
    std::vector<Eigen::Vector2d> uv;
    std::vector<double> t;
    const double t0 = ed.t.front(), t1 = ed.t.back();
    for (std::size_t k = 0; k < ed.t.size(); ++k) {
      uv.push_back(d.fit.uv_of(ed.points[k]));
      t.push_back(first + (last - first) * (ed.t[k] - t0) / (t1 - t0));
    }
    curve = compensated::fit_curve_2d(t, uv);
    return Standard_True;
  }
  Standard_Boolean NewParameter(const TopoDS_Vertex& v, const TopoDS_Edge& e,
                                Standard_Real& parameter, Standard_Real& tolerance) override {
    parameter = BRep_Tool::Parameter(v, e);  // the curves keep their edges' parameters
    tolerance = BRep_Tool::Tolerance(v);
    return Standard_True;
  }
  GeomAbs_Shape Continuity(const TopoDS_Edge& e, const TopoDS_Face& f1, const TopoDS_Face& f2,
                           const TopoDS_Edge&, const TopoDS_Face&, const TopoDS_Face&) override {
    return BRep_Tool::HasContinuity(e, f1, f2) ? BRep_Tool::Continuity(e, f1, f2) : GeomAbs_C0;
  }

 private:
  const FaceData& face(const TopoDS_Face& f) const {
    return s_.face[static_cast<std::size_t>(faces_.FindIndex(f) - 1)];
  }
  const EdgeData& edge(const TopoDS_Edge& e) const {
    return s_.edge[static_cast<std::size_t>(s_.edges.FindIndex(e) - 1)];
  }
  const Sampling& s_;
  const TopTools_IndexedMapOfShape& faces_;
  std::vector<Vec3> vertex_points_;
  bool loose_ = false;
};

// The shape rebuilt around the new geometry, its tolerances set by the gaps, and checked.
TopoDS_Shape rebuild(const CadShape& shape, const Sampling& s, bool loose, bool& valid) {
  const Handle(FieldModification) modification =
      new FieldModification(s, shape.impl().faces, s.vertex_points, loose);
  BRepTools_Modifier modifier(shape.impl().shape, modification);
  valid = false;
  if (!modifier.IsDone()) return {};
  const TopoDS_Shape result = modifier.ModifiedShape(shape.impl().shape);
  // The trimming curves were refitted apart from the edges: tolerances follow their gaps.
  BRepLib::SameParameter(result, 1e-5, Standard_True);
  BRepLib::UpdateTolerances(result, Standard_True);
  valid = BRepCheck_Analyzer(result).IsValid() == Standard_True;
  return result;
}

double percentile_95(std::vector<double> values) {
  if (values.empty()) return 0.0;
  const auto k = static_cast<std::size_t>(0.95 * static_cast<double>(values.size() - 1));
  std::nth_element(values.begin(), values.begin() + static_cast<long>(k), values.end());
  return values[k];
}

// One face: its coverage checked, its samples moved (with their allowances) and its boundary added.
Expected<bool> prepare_face(const TopoDS_Face& face, const CadFaceInfo& info, const Sampling& s,
                            const CompensatedShapeSettings& settings, FaceData& d) {
  d.report.id = info.id;
  std::size_t covered = 0;
  for (std::size_t k = 0; k < d.index.size(); ++k) {
    const auto i = static_cast<std::size_t>(d.index[k]);
    d.samples[k].moved = s.points[i] + s.offset[i];
    d.samples[k].allowance_mm = allowance(s, d.index[k], settings);
    covered += s.covered[i] ? 1 : 0;
    d.report.max_offset_mm = std::max(d.report.max_offset_mm, s.offset[i].norm());
  }
  d.report.coverage =
      d.index.empty() ? 1.0 : static_cast<double>(covered) / static_cast<double>(d.index.size());
  if (d.report.coverage < settings.min_face_coverage)
    return fail("compensated shape: the deformation field does not cover " + describe(info) + ": " +
                std::to_string(covered) + " of its " + std::to_string(d.index.size()) +
                " samples have a deformation vector nearby");
  add_boundary(face, d, s, settings);
  if (d.samples.empty())
    return fail(ErrorCode::kInternal,
                "compensated shape: face " + std::to_string(info.id) + " has no samples");
  return true;
}

// The planar faces of each flange of the segmentation fitted as one (fit_flange); a flange
// with a real form defect is left to the faces' own fits.
void fit_flanges(const CadShape& shape, Sampling& s, const CompensatedShapeSettings& settings) {
  const CadShape::Impl& impl = shape.impl();
  for (const Flange& flange : segment_cad(shape).flanges) {
    std::vector<TopoDS_Face> faces;
    std::vector<const std::vector<FaceSample>*> samples;
    bool seam = false;
    for (const int id : flange.face_ids) {
      faces.push_back(impl.face(id));
      samples.push_back(&s.face[static_cast<std::size_t>(id)].samples);
      seam = seam || s.face[static_cast<std::size_t>(id)].seam;
    }
    std::vector<FaceFit> fits;
    double worst = 0.0;
    if (seam || !compensated::fit_flange(faces, samples, settings, fits, worst)) continue;
    for (std::size_t f = 0; f < faces.size(); ++f) {
      FaceData& d = s.face[static_cast<std::size_t>(flange.face_ids[f])];
      d.fit = fits[f];
      d.report.flange = flange.id;
    }
  }
}

// The planes and cylinders among `faces` (the faces around an edge or a vertex).
std::vector<const FaceFit*> canonical_fits(const TopTools_ListOfShape& faces,
                                           const TopTools_IndexedMapOfShape& all,
                                           const Sampling& s) {
  std::vector<const FaceFit*> fits;
  for (TopTools_ListIteratorOfListOfShape it(faces); it.More(); it.Next()) {
    const FaceFit* fit = &s.face[static_cast<std::size_t>(all.FindIndex(it.Value()) - 1)].fit;
    if (!fit->same_parameters && std::find(fits.begin(), fits.end(), fit) == fits.end())
      fits.push_back(fit);
  }
  return fits;
}

// The moved vertices and edge samples put onto the planes and cylinders that replace their
// faces: the field's scatter those surfaces leave out would otherwise stay as a gap between an
// edge and its faces (edge tolerances of up to 0.2 mm on a sparse scan).
void project_onto_canonical(const CadShape::Impl& impl, Sampling& s) {
  TopTools_IndexedDataMapOfShapeListOfShape edge_faces, vertex_faces;
  TopExp::MapShapesAndAncestors(impl.shape, TopAbs_EDGE, TopAbs_FACE, edge_faces);
  TopExp::MapShapesAndAncestors(impl.shape, TopAbs_VERTEX, TopAbs_FACE, vertex_faces);
  s.vertex_points.resize(static_cast<std::size_t>(s.vertices.Extent()));
  for (int v = 1; v <= s.vertices.Extent(); ++v) {
    const auto i = static_cast<std::size_t>(v - 1);
    const int k = vertex_faces.FindIndex(s.vertices(v));
    const Vec3 moved = s.points[i] + s.offset[i];
    s.vertex_points[i] =
        k > 0 ? compensated::onto_surfaces(canonical_fits(vertex_faces(k), impl.faces, s), moved)
              : moved;
  }
  for (int e = 1; e <= s.edges.Extent(); ++e) {
    EdgeData& d = s.edge[static_cast<std::size_t>(e - 1)];
    const int k = edge_faces.FindIndex(s.edges(e));
    if (!d.moved || k == 0) continue;
    const std::vector<const FaceFit*> fits = canonical_fits(edge_faces(k), impl.faces, s);
    for (Vec3& p : d.points) p = compensated::onto_surfaces(fits, p);
    // The ends are the vertices (the first at the curve's first parameter).
    TopoDS_Vertex first, last;
    TopExp::Vertices(TopoDS::Edge(s.edges(e)), first, last);
    if (!first.IsNull())
      d.points.front() = s.vertex_points[static_cast<std::size_t>(s.vertices.FindIndex(first) - 1)];
    if (!last.IsNull())
      d.points.back() = s.vertex_points[static_cast<std::size_t>(s.vertices.FindIndex(last) - 1)];
  }
}

// A B-spline face refitted through its boundary as projected (project_onto_canonical).
void refit_bspline(const TopoDS_Face& face, const Sampling& s,
                   const CompensatedShapeSettings& settings, FaceData& d) {
  const double tried = d.fit.canonical_deviation_mm;  // of the plane/cylinder it is not
  d.samples.resize(d.index.size());
  add_boundary(face, d, s, settings);
  d.fit = compensated::fit_face(face, d.samples, d.box, false, settings);
  d.fit.canonical_deviation_mm = tried;
}

// A face's distances from its moved samples, and the limit on a B-spline's.
Expected<bool> check_face(const CadFaceInfo& info, const CompensatedShapeSettings& settings,
                          FaceData& d, std::vector<double>& deviations) {
  d.report.surface = d.fit.kind;
  d.report.canonical_deviation_mm = d.fit.canonical_deviation_mm;
  face_deviations(d, deviations);
  // A plane or cylinder lies within each sample's allowance by construction (fit_plane): only
  // a B-spline that cannot follow its samples fails here.
  if (d.fit.same_parameters && d.report.max_deviation_mm > settings.max_fit_deviation_mm)
    return fail(ErrorCode::kAnalysisFailed,
                "compensated shape: the refit of " + describe(info) + " lies " +
                    std::to_string(d.report.max_deviation_mm) +
                    " mm from its moved samples (limit " +
                    std::to_string(settings.max_fit_deviation_mm) + " mm)");
  return true;
}

// Samples, asks the field, checks coverage and refits every edge and face.
Expected<bool> refit(const CadShape& shape, const OffsetField& field, Sampling& s,
                     const CompensatedShapeSettings& settings, CompensatedShape& out,
                     std::vector<double>& deviations) {
  const CadShape::Impl& impl = shape.impl();
  TopExp::MapShapes(impl.shape, TopAbs_VERTEX, s.vertices);
  TopExp::MapShapes(impl.shape, TopAbs_EDGE, s.edges);
  for (int v = 1; v <= s.vertices.Extent(); ++v)
    s.add(BRep_Tool::Pnt(TopoDS::Vertex(s.vertices(v))));
  sample_edges(s, settings);
  s.face.resize(static_cast<std::size_t>(impl.faces.Extent()));
  for (int f = 0; f < impl.faces.Extent(); ++f) sample_face(impl.face(f), s.face[f], s, settings);
  if (auto asked = ask_field(s, field); !asked) return asked.error();
  auto moved = [&](int i) { return Vec3(s.points[i] + s.offset[i]); };
  for (const Vec3& o : s.offset) out.max_offset_mm = std::max(out.max_offset_mm, o.norm());
  for (const double u : s.uncertainty) out.max_uncertainty_mm = std::max(out.max_uncertainty_mm, u);
  for (EdgeData& e : s.edge)
    if (e.moved)
      for (const int i : e.index) e.points.push_back(moved(i));
  const std::vector<CadFaceInfo> info = describe_faces(shape);
  for (int f = 0; f < impl.faces.Extent(); ++f)
    if (auto done = prepare_face(impl.face(f), info[static_cast<std::size_t>(f)], s, settings,
                                 s.face[static_cast<std::size_t>(f)]);
        !done)
      return done.error();
  // Flanges as one, then every other face alone; edges and vertices onto the canonical faces,
  // the B-spline faces through them.
  fit_flanges(shape, s, settings);
  for (int f = 0; f < impl.faces.Extent(); ++f) {
    FaceData& d = s.face[static_cast<std::size_t>(f)];
    if (d.report.flange < 0)
      d.fit = compensated::fit_face(impl.face(f), d.samples, d.box, !d.seam, settings);
  }
  project_onto_canonical(impl, s);
  for (int f = 0; f < impl.faces.Extent(); ++f) {
    FaceData& d = s.face[static_cast<std::size_t>(f)];
    if (d.fit.same_parameters) {
      refit_bspline(impl.face(f), s, settings, d);
    } else {  // the boundary as projected: how far the face lies from its edges
      d.samples.resize(d.index.size());
      add_boundary(impl.face(f), d, s, settings);
    }
  }
  for (EdgeData& e : s.edge) {
    if (!e.moved) continue;
    e.curve = compensated::fit_curve(e.t, e.points, e.deviation);
    out.max_deviation_mm = std::max(out.max_deviation_mm, e.deviation);
    for (std::size_t k = 0; k < e.t.size(); ++k)
      deviations.push_back((v3(e.curve->Value(e.t[k]).XYZ()) - e.points[k]).norm());
  }
  for (int f = 0; f < impl.faces.Extent(); ++f) {
    FaceData& d = s.face[static_cast<std::size_t>(f)];
    if (auto done = check_face(info[static_cast<std::size_t>(f)], settings, d, deviations); !done)
      return done.error();
    out.max_deviation_mm = std::max(out.max_deviation_mm, d.report.max_deviation_mm);
    out.faces.push_back(d.report);
  }
  return true;
}

}  // namespace

Expected<CompensatedShape> compensated_shape(const CadShape& shape, const OffsetField& field,
                                             const CompensatedShapeSettings& settings) {
  if (shape.empty()) return fail("compensated shape: the CAD shape is empty");
  if (!field) return fail("compensated shape: no deformation field");
  try {
    CompensatedShape out;
    Sampling s;
    std::vector<double> deviations;
    if (auto done = refit(shape, field, s, settings, out, deviations); !done) return done.error();
    out.p95_deviation_mm = percentile_95(deviations);
    // Tight first: a plane's or cylinder's tolerance only covers its gap to its projected
    // edges. Where the checker then finds a trimming curve crossing itself (a pcurve refitted
    // along a flange-bend tangency, which the projection leaves to within the field's
    // scatter), the faces take that scatter as tolerance, as a B-spline face does.
    TopoDS_Shape result = rebuild(shape, s, false, out.valid);
    if (!out.valid) result = rebuild(shape, s, true, out.valid);
    for (TopExp_Explorer x(result, TopAbs_EDGE); x.More(); x.Next())
      out.max_tolerance_mm =
          std::max(out.max_tolerance_mm, BRep_Tool::Tolerance(TopoDS::Edge(x.Current())));
    for (TopExp_Explorer x(result, TopAbs_VERTEX); x.More(); x.Next())
      out.max_tolerance_mm =
          std::max(out.max_tolerance_mm, BRep_Tool::Tolerance(TopoDS::Vertex(x.Current())));
    if (!out.valid)
      return fail(ErrorCode::kAnalysisFailed,
                  "compensated shape: OpenCASCADE's checker (BRepCheck_Analyzer) finds the moved "
                  "shape invalid");
    CadLoadReport report;
    report.file = "(compensated)";
    report.format = "built";
    auto moved = make_cad_shape(result, report, CadImportSettings{});
    if (!moved) return moved.error();
    out.shape = std::move(moved).value();
    return out;
  } catch (const Standard_Failure& e) {
    return fail(ErrorCode::kAnalysisFailed,
                describe_occt_failure("compensated shape", e.GetMessageString()));
  }
}

}  // namespace springscan::analysis
