#pragma once
// The analysis pipeline: the DESIGN.md stages composed, one call per inspection. Used by
// `springscan analyze` and by the daemon's job runner.

#include "analysis/core/expected.hpp"
#include "analysis/core/part_model.hpp"
#include "analysis/core/point_cloud.hpp"
#include "analysis/matching/compensation.hpp"
#include "proto/springscan.pb.h"

namespace springscan::analysis {

struct InspectionOutcome {
  v1::InspectionReport report;  ///< every field DESIGN.md lists, timings included
  PointCloud deviation_cloud;   ///< scan points in the CAD frame, scalars = signed deviation
  Compensation compensation;    ///< at the k-center control points (compensation.csv/.ply)
  /// The CAD tessellation with every vertex moved by the interpolated compensation
  /// (compensated-surface.stl); empty when the model has no mesh.
  TriangleMesh compensated_surface;
};

/// Runs every stage on one scan. `settings` holds only overrides (proto `optional` fields);
/// each stage starts from its C++ defaults. Errors: unusable input (empty, degenerate, NaN).
/// Validates `settings` exactly as run_inspection and the part model loader do (every stage's
/// ranges, the model settings), without running anything: for config checks at load time.
/// Errors name the field and the bad value.
Expected<bool> check_analysis_settings(const v1::AnalysisSettings& settings);

Expected<InspectionOutcome> run_inspection(const PartModel& model, const PointCloud& scan,
                                           const v1::AnalysisSettings& settings = {});

}  // namespace springscan::analysis
