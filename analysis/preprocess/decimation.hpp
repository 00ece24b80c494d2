#pragma once
// Mesh decimation of a scanner triangulation (paper §2, its first reduction method): a vertex
// whose distance to its average plane (the least-squares plane of its neighbours) is below a
// threshold is deleted with its triangles and the hole is re-triangulated (Schroeder, Zarge and
// Lorensen 1992, the paper's reference /4/). Planar areas end up as a few large triangles,
// bends and the contour keep their vertices. Boundary vertices are never deleted (by default),
// so the reduced scan keeps the part's edges, which the boundary pinning of the global fit uses.
//
// The algorithm is VTK's vtkDecimatePro (docs/decimation.md says why this library); VTK is seen
// only by decimation.cpp. Vertices are not moved: every output vertex is an input vertex.

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "analysis/core/expected.hpp"
#include "analysis/core/point_cloud.hpp"

namespace springscan::analysis {

struct DecimationSettings {
  bool enabled = false;                   ///< the pipeline decimates mesh scans only when set
  double target_reduction = 0.9;          ///< share of the triangles to remove, [0, 0.99]
  double feature_angle_deg = 15.0;        ///< dihedral angle above which an edge is a feature
                                          ///< (a crease the decimation keeps), (0, 180]
  bool boundary_vertex_deletion = false;  ///< allow deleting contour vertices (paper: never)
  /// The decimation criterion, mm, in (0, 1000]: a vertex is deleted only while its distance to
  /// its average plane (to the line, on a crease), accumulated over the deletions around it,
  /// is below this. The reduction stops short of target_reduction where needed. On a
  /// noise-free surface it bounds the distance of the reduced mesh to the scanned points; on a
  /// noisy scan that distance exceeds it by up to a few noise sigmas (the re-triangulation
  /// joins noisy neighbours), see DecimationResult::max_deviation_mm.
  double max_error_mm = 0.05;
  int threads = 0;  ///< for the error measurement; 0: all cores (the result does not depend on it)
};

/// The settings' ranges (above). Errors (kInvalidSettings) name the field and the value.
Expected<bool> validate(const DecimationSettings& settings);

struct DecimationResult {
  TriangleMesh mesh;                  ///< the reduced mesh; its vertices are input vertices
  std::vector<std::uint32_t> kept;    ///< per output vertex: its index in the input mesh
  std::size_t input_triangles = 0;    ///< triangles in
  std::size_t isolated_vertices = 0;  ///< input vertices in no triangle: kept as they are
  double achieved_reduction = 0.0;    ///< 1 - triangles out / triangles in
  /// The largest distance of a deleted vertex to the reduced mesh, mm, measured afterwards:
  /// how far the reduced surface is from the scanned points.
  double max_deviation_mm = 0.0;
};

/// Checks a mesh before decimation: at least one triangle, finite vertices within 1e9 mm,
/// indices in range, no triangle that names a vertex twice, an oriented manifold (no directed
/// edge in two triangles: no repeated triangle, no inconsistent winding, at most two triangles
/// on an edge), fewer than 2^31 vertices and triangles, and triangles spanning no more than 10^4
/// times their median edge (a stray vertex far from the surface; vtkDecimatePro's tolerance is
/// relative to the box and would swallow the mesh's triangles). Errors are kInvalidInput and
/// name the triangle or vertex and the value. O(n log n).
Expected<bool> check_mesh(const TriangleMesh& mesh);

/// Decimates `mesh` (check_mesh first). Deterministic. Reentrant: the VTK objects it uses are
/// local to the call, so concurrent calls on different meshes are safe. O(n log n).
/// Errors: check_mesh's, validate's, and a VTK failure (kAnalysisFailed, with its message).
Expected<DecimationResult> decimate_mesh(const TriangleMesh& mesh,
                                         const DecimationSettings& settings = {});

/// A scan given as a mesh reduced to the vertices decimate_mesh keeps, with their attributes
/// (normals, colours, scalars, face ids) in `cloud`'s order. `triangles` index `cloud.points`.
struct DecimatedScan {
  PointCloud cloud;         ///< the kept vertices
  DecimationResult result;  ///< the reduced mesh and the figures
};
Expected<DecimatedScan> decimate_scan(const PointCloud& cloud,
                                      const std::vector<std::array<std::uint32_t, 3>>& triangles,
                                      const DecimationSettings& settings = {});

}  // namespace springscan::analysis
