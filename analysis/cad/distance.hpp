#pragma once
// Exact signed distance from points to the CAD surface (DESIGN.md stage 5: "exact
// projection on the face, sign by the face normal").

#include <memory>
#include <vector>

#include "analysis/cad/import.hpp"
#include "analysis/core/part_model.hpp"

namespace springscan::analysis {

struct CadDistanceSettings {
  /// Extra distance (mm) beyond each face's tessellation deflection within which a face is
  /// still refined on its true surface. Larger is safer and slower.
  double candidate_margin_mm = 1e-3;
  int bvh_leaf_size = 4;  ///< triangles per BVH leaf
};

/// A SurfaceDistance over a CadShape. Each query:
///  1. finds the nearest tessellation triangle (BVH) and every face with a triangle within
///     that distance plus twice the face's deflection plus candidate_margin_mm;
///  2. refines each candidate on its true surface: closed form for planes and cylinders, a
///     Newton projection (Extrema_GenLocateExtPS) seeded by the triangle for other surfaces;
///  3. keeps the foot when it lies inside the face's trimmed domain (its UV triangulation, or
///     BRepClass_FaceClassifier near trimmed curves), else the closest point of the face's
///     boundary edges;
///  4. returns the closest foot; signed_distance_mm > 0 on the side the outward face normal
///     points to (out of a solid; for a shell, the side its face orientation marks).
/// Accuracy: exact up to rounding for planes and cylinders, Extrema's tolerance (1e-9 in
/// parameter) otherwise. Thread-safe: closest() may be called from any number of threads.
/// The returned object keeps the shape alive.
std::shared_ptr<const SurfaceDistance> make_cad_distance(const CadShape& shape,
                                                         const CadDistanceSettings& settings = {});

/// closest() of every point, on `threads` threads (0 = hardware concurrency), in the point
/// loops' blocks (core/parallel.hpp). Each point's hit is its own, so the result does not depend
/// on the thread count.
std::vector<SurfaceHit> closest_all(const SurfaceDistance& distance,
                                    const std::vector<Vec3>& points, int threads = 0);

}  // namespace springscan::analysis
