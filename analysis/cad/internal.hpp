#pragma once
// PRIVATE to analysis/cad/: the OpenCASCADE side of CadShape. This is the one header that
// includes OpenCASCADE; it is never included by a public header or outside analysis/cad/
// (STYLE.md section 1: foreign types stay in adapter files at the folder's edge).
//
// Threads and OpenCASCADE. OCCT 7.6 objects are safe to share between threads only while nothing
// writes them, and some write themselves inside const queries. Audited: every parallel loop that
// reaches OpenCASCADE does so through SurfaceDistance::closest (CadDistance, cad/distance.cpp):
// signed_deviation (deviation/deviation.cpp, parallel_blocks), closest_all (cad/distance.cpp,
// parallel_blocks) and the exact-surface pairs of the local fits (springback/local_fit.cpp
// find_pair, for_each_block). inspection/pipeline.cpp only composes these stages. Import, meshing,
// sampling (cad/sampling.cpp), segmentation (cad/segmentation*.cpp), the model cache
// (cad/model.cpp) and the test parts' profile solids (simulators/parts/cad_profile.cpp) run on
// the caller's thread and share nothing with concurrent queries except the objects below. The
// parallel loops of the produced test parts (simulators/parts/produced_part.cpp, laser_scan.cpp)
// read only our copies (CadMesh, CadFaceInfo), never an OpenCASCADE object.
//  - Shared, read only, safe: the TopoDS shape and its faces and edges (Impl::shape, faces,
//    DistanceTables::edge_map). Queries only read them (TopExp_Explorer, BRep_Tool,
//    NCollection_IndexedMap::FindKey, which reads its node array); copying a shape or a handle
//    changes Standard_Transient's reference count, which OCCT updates atomically. BRepMesh
//    writes triangulations into the shape in make_cad_shape, before the shape is shared.
//    Geom_* surfaces and curves are immutable under evaluation (OCCT 7.x keeps B-spline
//    evaluation caches in the adaptors, not in Geom_BSplineSurface/Curve); BRep_Tool::Surface
//    of a located face returns a fresh transformed copy.
//  - Built per call, owned by the calling thread, safe: BRepAdaptor_Surface and
//    BRepAdaptor_Curve (with their B-spline caches), Extrema_GenLocateExtPS, Extrema_ExtPC,
//    GeomAPI_ProjectPointOnSurf, BRepLProp_SLProps (cad/distance_faces.cpp, cad/sampling.cpp),
//    BRepClass_FaceClassifier (cad/segmentation.cpp point_projects_into).
//  - Shared and written by a const query, NOT safe: BRepTopAdaptor_FClass2d. Perform() reads
//    its boundary polygons through NCollection_Sequence::Value() const, which stores the
//    sequence's "current node" cache (myCurrentItem, myCurrentIndex: NCollection_Sequence.hxx
//    casts away const). Two threads interleave those stores and one walks from the other's
//    node: `springscan analyze` crashed there one run in four to twelve. Hence
//    FaceClassifierPool: one classifier per thread at a time. Its answers do not depend on which
//    classifier or how many: every one is built from the same face and tolerance, and the cache
//    only speeds up the walk.
//  - Process-wide: the data-exchange parameters (Interface_Static) behind
//    occt_exchange_mutex(); OCCT's error-handler stack is per thread (Standard_ErrorHandler)
//    and its memory manager is thread-safe, so Standard_Failure may be thrown in any worker.
// Our own tables (AnalyticSurface, CadMesh, trim_sides, UvGrid, EdgeData, TriangleBvh) are plain
// data, written once before the first query. ThreadSanitizer (scripts/test.sh tsan) cannot see a
// race inside OpenCASCADE, which is not instrumented; tests/analysis/cad/distance_threads_test.cpp
// compares threaded queries near curved trims with serial ones bit for bit instead.

#include <BRepTopAdaptor_FClass2d.hxx>
#include <TopTools_IndexedMapOfShape.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Face.hxx>
#include <TopoDS_Shape.hxx>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "analysis/cad/import.hpp"

namespace springscan::analysis {

/// A face's surface in closed form, when it is a plane or a circular cylinder (also as a surface
/// of revolution of a parallel line or a linear extrusion of a circle, as IGES often stores
/// them), in the face's own (u, v) parametrisation so that mesh UV nodes map onto it:
///   plane     P(u, v) = origin + u x + v y
///   cylinder  P(u, v) = origin + radius (cos u x + sin u y) + (v_offset + v_scale v) z
/// `sense` is +1 for FORWARD faces and -1 for REVERSED ones: outward normal = sense * Pu x Pv.
struct AnalyticSurface {
  enum class Kind { kPlane, kCylinder, kOther };
  Kind kind = Kind::kOther;
  Vec3 origin = Vec3::Zero();
  Vec3 x = Vec3::UnitX();
  Vec3 y = Vec3::UnitY();
  Vec3 z = Vec3::UnitZ();
  double radius = 0.0;
  double v_offset = 0.0;
  double v_scale = 1.0;
  double sense = 1.0;

  Vec3 point(const Eigen::Vector2d& uv) const;
  /// Unit outward normal at (u, v) (plane: constant).
  Vec3 normal(const Eigen::Vector2d& uv) const;
  /// The foot of p on the untrimmed surface and its (u, v); u in (-pi, pi] for cylinders.
  Eigen::Vector2d project(const Vec3& p, Vec3& foot) const;
};

AnalyticSurface analytic_surface(const TopoDS_Face& face);

/// The exact UV classifiers of one face (a fine boundary polygon, with BRepClass_FaceClassifier
/// only inside its tolerance band), handed out one per concurrent caller because
/// BRepTopAdaptor_FClass2d is not safe to share (see the top of this file). The first classifier
/// is built with the pool, so a face OpenCASCADE cannot classify fails at load; more are built
/// lazily when all are in use, at most one per thread that classifies on this face at the
/// same time, and kept for later calls. Thread-safe: the mutex guards only the free list,
/// classification runs unlocked on a classifier no other thread holds.
class FaceClassifierPool {
 public:
  FaceClassifierPool(const TopoDS_Face& face, double tolerance);
  FaceClassifierPool(const FaceClassifierPool&) = delete;
  FaceClassifierPool& operator=(const FaceClassifierPool&) = delete;

  /// True when (u, v) lies inside the trimmed face or on its boundary.
  bool inside(const Eigen::Vector2d& uv) const;

 private:
  std::unique_ptr<BRepTopAdaptor_FClass2d> take() const;
  void give_back(std::unique_ptr<BRepTopAdaptor_FClass2d> classifier) const;

  TopoDS_Face face_;
  double tolerance_;
  mutable std::mutex mutex_;
  // Guarded by mutex_: the classifiers no thread holds, and how many exist (free_'s capacity
  // is kept at least that, so returning one never allocates).
  mutable std::vector<std::unique_ptr<BRepTopAdaptor_FClass2d>> free_;
  mutable std::size_t built_ = 0;
};

/// Immutable after construction, except inside the classifier pools, which synchronise
/// themselves: every query reads it concurrently.
struct CadShape::Impl {
  TopoDS_Shape shape;
  TopTools_IndexedMapOfShape faces;  ///< face id i (0-based) = faces(i + 1)
  CadLoadReport report;
  CadMesh mesh;
  std::vector<AnalyticSurface> surfaces;  ///< per face
  /// Per triangle, bit k: side (k, k+1) lies on the boundary of a face with a curved trimming
  /// edge (not a line in UV). Its chord may cut across the true boundary by up to the edge
  /// deflection, so points within trim_band_mm of it are classified exactly.
  std::vector<std::uint8_t> trim_sides;
  double trim_band_mm = 0.0;
  /// Per face with a curved trim, its classifiers (null for the other faces).
  std::vector<std::unique_ptr<FaceClassifierPool>> classifiers;

  const TopoDS_Face& face(int id) const { return TopoDS::Face(faces(id + 1)); }
};

/// OpenCASCADE's data exchange keeps its parameters (units, modes) in process-wide statics
/// (Interface_Static), so every reader and writer call holds this lock.
std::mutex& occt_exchange_mutex();

/// Heals nothing and reads nothing: counts, measures and tessellates `shape` into a CadShape.
/// `report` carries what the caller already knows (file, format, sewing, scale).
Expected<CadShape> make_cad_shape(const TopoDS_Shape& shape, CadLoadReport report,
                                  const CadImportSettings& settings);

/// Fills surfaces, trim_sides, trim_band_mm and classifiers (cad/trim.cpp).
void prepare_trimming(CadShape::Impl& shape, double linear_deflection_mm);

/// True when (u, v), found in mesh triangle `triangle` of face `face_id` (or -1: in no
/// triangle), lies inside the trimmed face or on its boundary. Exact: the UV triangulation
/// decides where it is exact, the classifier near curved trims. Thread-safe; takes a lock
/// (of the face's classifier pool) only when it classifies.
bool inside_trimmed(const CadShape::Impl& shape, int face_id, int triangle,
                    const Eigen::Vector2d& uv);

/// "what: message" for an OpenCASCADE exception.
std::string describe_occt_failure(const std::string& what, const char* message);

}  // namespace springscan::analysis
