#pragma once
// CAD import through OpenCASCADE: IGES, STEP and OpenCASCADE .brep files read into a
// healed, tessellated CadShape, lengths in millimetres. Only our own types appear here; the
// OpenCASCADE side lives in analysis/cad_*.cpp.

#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "analysis/core/expected.hpp"
#include "analysis/core/point_cloud.hpp"

namespace springscan::analysis {

struct CadImportSettings {
  double sewing_tolerance_mm = 0.01;  ///< gap closed when loose faces are sewn into shells
  bool sew_loose_faces = true;        ///< sew faces that belong to no shell (typical of IGES)
  bool heal = true;                   ///< run ShapeFix_Shape (tolerances, wires, orientation)
  /// A part whose bounding-box diagonal is below this after unit conversion is taken to be
  /// written in metres under a millimetre header (e.g. OCCT's bearing.iges) and scaled by 1000.
  /// Press-line parts are never this small; 0 disables the rule.
  double min_plausible_size_mm = 1.0;
  double linear_deflection_mm = 0.05;    ///< tessellation chord tolerance (BRepMesh)
  double angular_deflection_deg = 10.0;  ///< tessellation angle tolerance between triangles
};

/// What the import found, for `springscan model` and for logs.
struct CadLoadReport {
  std::string file;    ///< the path as given
  std::string format;  ///< "IGES", "STEP", "BREP" or "built" (made in memory)
  int faces = 0;
  int shells = 0;
  int solids = 0;
  int free_edges = 0;  ///< edges bounding only one face: open boundaries, gaps
  double area_mm2 = 0.0;
  Vec3 bbox_min = Vec3::Zero();
  Vec3 bbox_max = Vec3::Zero();
  bool sewn = false;           ///< loose faces were sewn
  bool healed = false;         ///< ShapeFix_Shape ran
  double scale_applied = 1.0;  ///< extra factor of the metre-scale rule (1 or 1000)
  int triangles = 0;
  int faces_without_mesh = 0;  ///< faces BRepMesh could not tessellate (never sampled)
};

/// The tessellation in our types. Triangles wind counter-clockwise around the face's outward
/// normal (REVERSED faces already flipped). uv: each vertex's surface parameters on its face.
struct CadMesh {
  std::vector<Vec3> vertices;
  std::vector<Eigen::Vector2d> uv;
  std::vector<std::array<std::uint32_t, 3>> triangles;
  std::vector<std::int32_t> triangle_faces;  ///< face id per triangle
  std::vector<double> face_deflection_mm;    ///< achieved chord deviation per face (0: no mesh)
};

/// A loaded CAD shape. Face ids are 0-based: id i is the (i+1)-th face of
/// TopExp::MapShapes(shape, TopAbs_FACE), stable for a given file.
/// Copies share one immutable shape: every const member may be called from many threads.
class CadShape {
 public:
  struct Impl;
  CadShape() = default;
  explicit CadShape(std::shared_ptr<const Impl> impl) : impl_(std::move(impl)) {}

  bool empty() const { return impl_ == nullptr; }
  int face_count() const;
  const CadLoadReport& report() const;
  const CadMesh& mesh() const;
  const Impl& impl() const { return *impl_; }

 private:
  std::shared_ptr<const Impl> impl_;
};

/// Reads IGES (.igs/.iges), STEP (.stp/.step) or OpenCASCADE BRep (.brep/.brp), converts to
/// millimetres, sews loose faces, heals and tessellates. Errors name the file and the step that
/// failed (missing, unreadable, unsupported extension, no faces). Serialised internally:
/// OpenCASCADE's readers share process-wide parameters.
Expected<CadShape> load_cad(const std::string& path, const CadImportSettings& settings = {});

/// The shape as OpenCASCADE BRep text (the model cache stores it).
std::string cad_to_brep_text(const CadShape& shape);

/// Rebuilds a CadShape from BRep text (no sewing, healing or unit rules: the text is already
/// in mm). `name` is used in errors and the report.
Expected<CadShape> cad_from_brep_text(const std::string& text, const std::string& name,
                                      const CadImportSettings& settings = {});

/// "faces 16, shells 1, solids 1, free edges 0, area ... mm2, bbox ... mm": one line for logs.
std::string summary(const CadLoadReport& report);

}  // namespace springscan::analysis
