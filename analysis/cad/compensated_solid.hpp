#pragma once
// The compensated die surface (DESIGN.md "Compensated die surface", docs/matching.md
// "Compensated CAD"): every face, edge and vertex of a CAD shape moved by a displacement field
// (the displacement adjustment method: -F x the measured deformation), refitted and kept in one
// topology, so the result is the same solid or shell with the same faces, written as STEP.
//
// Each face is sampled on a grid over its (u, v) range and the moved grid is refitted:
//  - the planar faces of one flange of the segmentation are fitted together: one normal, one
//    plane per side of the sheet, so a rigidly moved flange stays one flange;
//  - a plane that stays a plane (a circular cylinder that stays one) is written as that plane
//    (cylinder): a rigidly moved flange, an over-bent bend; the segmentation then finds the same
//    flanges and bends on re-import. "Stays" is judged per sample against the field's own
//    uncertainty there: canonical_tolerance_mm + uncertainty_factor x the field's scatter, so
//    a sparser, noisier field keeps the flanges planes, while a form defect the field measures
//    well (smoothly, larger than that) still makes a B-spline;
//  - any other face becomes a cubic B-spline surface fitted by least squares in the face's own
//    (u, v) parametrisation, so its trimming curves stay as they are.
// Edges get B-spline curves through their moved samples at their own parameters, vertices move
// with the field, trimming curves on the canonical faces are mapped through the moved surface.
// The shape keeps its topology (OpenCASCADE's BRepTools_Modifier), so no sewing can lose or
// merge a face. The result is checked with BRepCheck_Analyzer.
//
// Thread safety: pure functions of their inputs; the offset callback is called on the caller's
// thread only.

#include <functional>
#include <string>
#include <vector>

#include "analysis/cad/import.hpp"
#include "analysis/core/expected.hpp"
#include "analysis/core/point_cloud.hpp"

namespace springscan::analysis {

/// The displacement at a batch of points (CAD frame, mm): offset[i] is added to points[i].
/// covered[i] false: the field has no value there (offset ignored).
struct PointOffsets {
  std::vector<Vec3> offset;
  std::vector<bool> covered;
  /// How well offset[i] is known (mm, the field's local scatter, FieldAtPoints::spread_mm);
  /// empty: exactly.
  std::vector<double> uncertainty_mm;
};
using OffsetField = std::function<PointOffsets(const std::vector<Vec3>& points)>;

struct CompensatedShapeSettings {
  int face_samples = 21;  ///< grid samples per direction of each face (u and v)
  int face_spans = 8;     ///< cubic spans per direction of a B-spline face (doubled up to 32
                          ///< while the refit lies farther than bspline_tolerance_mm)
  double bspline_tolerance_mm = 0.01;   ///< the B-spline refit's aim (max over its samples)
  int edge_samples = 41;                ///< samples along each edge
  double canonical_tolerance_mm = 0.1;  ///< a moved plane/cylinder within this stays one
  /// ... plus this many times the field's uncertainty at each sample (PointOffsets).
  double uncertainty_factor = 3.0;
  /// The share of a face's (a flange's) samples that must lie within that allowance. Not all:
  /// where the field extrapolates (a corner the scan barely reaches) a few samples stray by
  /// more than its scatter says; a real form defect covers a region, not a few samples.
  double canonical_share = 0.95;
  /// ... and none of them farther than this (mm): the bound on a plane's or cylinder's
  /// deviation from the moved samples.
  double max_canonical_deviation_mm = 0.3;
  /// A face with fewer of its samples covered by the field is refused (the error names it);
  /// its other uncovered samples take the offset of the nearest covered sample.
  double min_face_coverage = 0.5;
  double max_fit_deviation_mm = 0.15;  ///< a refit farther than this from its samples fails
};

/// One face of the result.
struct CompensatedFace {
  int id = 0;                     ///< face id, as in the input (and the output) shape
  std::string surface;            ///< "plane", "cylinder" or "bspline"
  double max_deviation_mm = 0.0;  ///< of the refit from the moved samples
  double max_offset_mm = 0.0;     ///< longest displacement applied on the face
  double coverage = 1.0;          ///< share of its samples the field covered
  /// A plane or cylinder: how far the moved samples lie from the best one (-1: not tried, e.g.
  /// a B-spline face); above canonical_tolerance_mm the face became a B-spline.
  double canonical_deviation_mm = -1.0;
  int flange = -1;  ///< the flange of the segmentation fitted as one (-1: fitted alone)
};

struct CompensatedShape {
  CadShape shape;  ///< the moved shape, tessellated (face ids as the input's)
  std::vector<CompensatedFace> faces;
  double max_deviation_mm = 0.0;  ///< refit vs moved samples, over faces and edges
  double p95_deviation_mm = 0.0;
  double max_offset_mm = 0.0;       ///< longest displacement applied
  double max_uncertainty_mm = 0.0;  ///< largest field uncertainty at a sample
  /// The result's largest edge or vertex tolerance (mm): how far the refitted edges lie from
  /// the faces they bound (BRepLib::SameParameter).
  double max_tolerance_mm = 0.0;
  bool valid = false;  ///< BRepCheck_Analyzer found the shape valid
};

/// Moves `shape` by `offsets`. Errors: an empty shape, a face the field does not cover
/// (kInvalidInput, naming the face id, its type and its centroid), a refit beyond
/// max_fit_deviation_mm, an invalid result (kAnalysisFailed), OpenCASCADE failures.
Expected<CompensatedShape> compensated_shape(const CadShape& shape, const OffsetField& offsets,
                                             const CompensatedShapeSettings& settings = {});

/// Writes `shape` as STEP (AP214, mm) to `path` atomically: the file appears complete or not at
/// all (write_file_atomically), an existing file is left as it was on error.
Expected<bool> write_step_atomically(const CadShape& shape, const std::string& path);

}  // namespace springscan::analysis
