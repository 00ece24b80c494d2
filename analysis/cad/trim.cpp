// Exact inside tests for trimmed faces: the UV triangulation is exact where the face boundary is
// straight in UV; near curved trims (holes in planes, cut-outs) the chords are checked against
// OpenCASCADE's face classifier, one per thread at a time (FaceClassifierPool, cad/internal.hpp).
#include <BRepAdaptor_Curve2d.hxx>
#include <BRep_Tool.hxx>
#include <TopExp_Explorer.hxx>
#include <algorithm>
#include <map>

#include "analysis/cad/internal.hpp"

namespace springscan::analysis {
namespace {

bool has_curved_trim(const TopoDS_Face& face) {
  for (TopExp_Explorer it(face, TopAbs_EDGE); it.More(); it.Next()) {
    const TopoDS_Edge& edge = TopoDS::Edge(it.Current());
    if (BRep_Tool::Degenerated(edge)) continue;
    if (BRepAdaptor_Curve2d(edge, face).GetType() != GeomAbs_Line) return true;
  }
  return false;
}

// UV to a metric 2-D frame where it is one (planes: already mm; cylinders: u times the radius),
// so that a distance in UV is a distance on the surface.
bool metric_uv(const AnalyticSurface& s, const Eigen::Vector2d& uv, Eigen::Vector2d& out) {
  if (s.kind == AnalyticSurface::Kind::kPlane) {
    out = uv;
    return true;
  }
  if (s.kind == AnalyticSurface::Kind::kCylinder) {
    out = Eigen::Vector2d(uv.x() * s.radius, uv.y() * std::abs(s.v_scale));
    return true;
  }
  return false;
}

double segment_distance(const Eigen::Vector2d& p, const Eigen::Vector2d& a,
                        const Eigen::Vector2d& b) {
  const Eigen::Vector2d d = b - a;
  const double t =
      d.squaredNorm() > 0 ? std::clamp((p - a).dot(d) / d.squaredNorm(), 0.0, 1.0) : 0.0;
  return (p - (a + t * d)).norm();
}

bool classify(const CadShape::Impl& shape, int face_id, const Eigen::Vector2d& uv) {
  const auto& pool = shape.classifiers[static_cast<std::size_t>(face_id)];
  return pool && pool->inside(uv);
}

}  // namespace

FaceClassifierPool::FaceClassifierPool(const TopoDS_Face& face, double tolerance)
    : face_(face), tolerance_(tolerance), built_(1) {
  free_.push_back(std::make_unique<BRepTopAdaptor_FClass2d>(face_, tolerance_));
}

std::unique_ptr<BRepTopAdaptor_FClass2d> FaceClassifierPool::take() const {
  {
    const std::lock_guard<std::mutex> lock(mutex_);
    if (!free_.empty()) {
      auto classifier = std::move(free_.back());
      free_.pop_back();
      return classifier;
    }
    // Room for this one's return, so that give_back, which runs in a destructor, never
    // allocates.
    free_.reserve(++built_);
  }
  // Every classifier is held by another thread: build one more, outside the lock (it
  // polygonises the whole boundary), from the shared face, which construction only reads.
  return std::make_unique<BRepTopAdaptor_FClass2d>(face_, tolerance_);
}

void FaceClassifierPool::give_back(std::unique_ptr<BRepTopAdaptor_FClass2d> classifier) const {
  const std::lock_guard<std::mutex> lock(mutex_);
  free_.push_back(std::move(classifier));
}

bool FaceClassifierPool::inside(const Eigen::Vector2d& uv) const {
  // The classifier goes back also when Perform throws (Standard_Failure): its only state
  // besides what construction computed is the boundary sequences' access cache.
  struct Lease {
    const FaceClassifierPool& pool;
    std::unique_ptr<BRepTopAdaptor_FClass2d> classifier;
    ~Lease() { pool.give_back(std::move(classifier)); }
  } lease{*this, take()};
  const TopAbs_State state = lease.classifier->Perform(gp_Pnt2d(uv.x(), uv.y()));
  return state == TopAbs_IN || state == TopAbs_ON;
}

void prepare_trimming(CadShape::Impl& impl, double linear_deflection_mm) {
  const CadMesh& mesh = impl.mesh;
  const auto face_count = static_cast<std::size_t>(impl.faces.Extent());
  impl.surfaces.resize(face_count);
  impl.classifiers.resize(face_count);
  std::vector<bool> curved(face_count);
  for (std::size_t f = 0; f < face_count; ++f) {
    const TopoDS_Face& face = impl.face(static_cast<int>(f));
    impl.surfaces[f] = analytic_surface(face);
    curved[f] = has_curved_trim(face);
    if (curved[f]) impl.classifiers[f] = std::make_unique<FaceClassifierPool>(face, 1e-9);
  }
  // BRepMesh keeps edge chords within the linear deflection; twice that is a safe band.
  impl.trim_band_mm = 2.0 * linear_deflection_mm;
  // A triangle side used by no other triangle of the face lies on the face boundary (each face
  // has its own mesh nodes).
  std::map<std::pair<std::uint32_t, std::uint32_t>, int> side_uses;
  for (const auto& t : mesh.triangles)
    for (int k = 0; k < 3; ++k) ++side_uses[std::minmax(t[k], t[(k + 1) % 3])];
  impl.trim_sides.assign(mesh.triangles.size(), 0);
  for (std::size_t i = 0; i < mesh.triangles.size(); ++i) {
    if (!curved[static_cast<std::size_t>(mesh.triangle_faces[i])]) continue;
    const auto& t = mesh.triangles[i];
    for (int k = 0; k < 3; ++k)
      if (side_uses[std::minmax(t[k], t[(k + 1) % 3])] == 1)
        impl.trim_sides[i] = static_cast<std::uint8_t>(impl.trim_sides[i] | (1u << k));
  }
}

bool inside_trimmed(const CadShape::Impl& shape, int face_id, int triangle,
                    const Eigen::Vector2d& uv) {
  if (triangle < 0) return classify(shape, face_id, uv);
  const auto t = static_cast<std::size_t>(triangle);
  const std::uint8_t sides = shape.trim_sides[t];
  if (sides == 0) return true;
  const AnalyticSurface& surface = shape.surfaces[static_cast<std::size_t>(face_id)];
  Eigen::Vector2d p = Eigen::Vector2d::Zero();
  if (!metric_uv(surface, uv, p)) return classify(shape, face_id, uv);
  const auto& tri = shape.mesh.triangles[t];
  for (int k = 0; k < 3; ++k) {
    if (!(sides & (1u << k))) continue;
    Eigen::Vector2d a = Eigen::Vector2d::Zero(), b = Eigen::Vector2d::Zero();
    metric_uv(surface, shape.mesh.uv[tri[static_cast<std::size_t>(k)]], a);
    metric_uv(surface, shape.mesh.uv[tri[static_cast<std::size_t>((k + 1) % 3)]], b);
    if (segment_distance(p, a, b) <= shape.trim_band_mm) return classify(shape, face_id, uv);
  }
  return true;
}

}  // namespace springscan::analysis
