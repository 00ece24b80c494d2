#pragma once
// PRIVATE to analysis/cad_*.cpp: the OpenCASCADE side of CadShape. This is the one header that
// includes OpenCASCADE; it is never included by a public header or outside analysis/cad_*.cpp
// (STYLE.md section 1: foreign types stay in adapter files at the folder's edge).

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

/// Immutable after construction: every query reads it concurrently.
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
  /// Per face with a curved trim: a UV classifier built once (a fine boundary polygon, with the
  /// exact BRepClass_FaceClassifier only inside its tolerance band). Perform() is const.
  std::vector<std::unique_ptr<BRepTopAdaptor_FClass2d>> classifiers;

  const TopoDS_Face& face(int id) const { return TopoDS::Face(faces(id + 1)); }
};

/// OpenCASCADE's data exchange keeps its parameters (units, modes) in process-wide statics
/// (Interface_Static), so every reader and writer call holds this lock.
std::mutex& occt_exchange_mutex();

/// Heals nothing and reads nothing: counts, measures and tessellates `shape` into a CadShape.
/// `report` carries what the caller already knows (file, format, sewing, scale).
Expected<CadShape> make_cad_shape(const TopoDS_Shape& shape, CadLoadReport report,
                                  const CadImportSettings& settings);

/// Fills surfaces, trim_sides, trim_band_mm and classifiers (cad_trim.cpp).
void prepare_trimming(CadShape::Impl& shape, double linear_deflection_mm);

/// True when (u, v), found in mesh triangle `triangle` of face `face_id` (or -1: in no
/// triangle), lies inside the trimmed face or on its boundary. Exact: the UV triangulation
/// decides where it is exact, the classifier near curved trims. Thread-safe.
bool inside_trimmed(const CadShape::Impl& shape, int face_id, int triangle,
                    const Eigen::Vector2d& uv);

/// "what: message" for an OpenCASCADE exception.
std::string describe_occt_failure(const std::string& what, const char* message);

}  // namespace springscan::analysis
