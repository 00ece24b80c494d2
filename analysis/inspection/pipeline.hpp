#pragma once
// The analysis pipeline: the DESIGN.md stages composed, one call per inspection. Used by
// `springscan analyze` and by the daemon's job runner.

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "analysis/core/expected.hpp"
#include "analysis/core/part_model.hpp"
#include "analysis/core/point_cloud.hpp"
#include "analysis/matching/compensation.hpp"
#include "proto/springscan.pb.h"

namespace springscan::analysis {

/// What the mesh decimation did to a scan given as a mesh (run_mesh_inspection).
struct MeshScanReduction {
  bool decimated = false;  ///< reduction.mesh_decimation.enabled was set
  std::size_t vertices_in = 0;
  std::size_t triangles_in = 0;
  std::size_t vertices_out = 0;    ///< the scan points the pipeline ran on
  std::size_t triangles_out = 0;   ///< of the reduced mesh
  double max_deviation_mm = -1.0;  ///< deleted vertices to the reduced mesh; -1: not measured
  double time_ms = 0.0;            ///< also in report.timings_ms.reduce
};

struct InspectionOutcome {
  v1::InspectionReport report;  ///< every field DESIGN.md lists, timings included
  PointCloud deviation_cloud;   ///< scan points in the CAD frame, scalars = signed deviation
  Compensation compensation;    ///< at the k-center control points (compensation.csv/.ply)
  /// The CAD tessellation with every vertex moved by the interpolated compensation
  /// (compensated-surface.stl); empty when the model has no mesh.
  TriangleMesh compensated_surface;
  MeshScanReduction mesh_reduction;  ///< run_mesh_inspection only
};

/// Runs every stage on one scan. `settings` holds only overrides (proto `optional` fields);
/// each stage starts from its C++ defaults. Errors: unusable input (empty, degenerate, NaN).
/// Validates `settings` exactly as run_inspection and the part model loader do (every stage's
/// ranges, the model settings), without running anything: for config checks at load time.
/// Errors name the field and the bad value.
Expected<bool> check_analysis_settings(const v1::AnalysisSettings& settings);

Expected<InspectionOutcome> run_inspection(const PartModel& model, const PointCloud& scan,
                                           const v1::AnalysisSettings& settings = {});

/// run_inspection on a scan given as a triangulation (a scanner's STL, a PLY with faces):
/// `triangles` index `scan.points`. With reduction.mesh_decimation.enabled, the vertices the
/// decimation keeps (paper §2, analysis/preprocess/decimation.hpp), with their attributes, are
/// the scan; otherwise every vertex is, exactly as run_inspection(model, scan, settings).
/// Errors: run_inspection's, and a mesh decimate_mesh refuses (named, kInvalidInput).
Expected<InspectionOutcome> run_mesh_inspection(
    const PartModel& model, const PointCloud& scan,
    const std::vector<std::array<std::uint32_t, 3>>& triangles,
    const v1::AnalysisSettings& settings = {});

}  // namespace springscan::analysis
