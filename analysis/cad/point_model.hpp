#pragma once
// A PartModel from a model point cloud (`springscan analyze --model MODEL.ply`, tests): the
// points are the samples, normals estimated when the file has none. No segmentation, no exact
// distance (the deviation then uses the samples' tangent planes).

#include <cstddef>

#include "analysis/core/expected.hpp"
#include "analysis/core/part_model.hpp"
#include "analysis/preprocess/normals.hpp"

namespace springscan::analysis {

struct PointModelSettings {
  NormalSettings normals;  ///< used when the cloud has no normals; orientation decides the sign
                           ///< of deviations (default: towards a viewpoint far above +z)
};

struct PointModelOutcome {
  PartModel model;
  bool normals_estimated = false;  ///< false: the file's normals (normalised) were used
  std::size_t dropped = 0;         ///< points without a usable normal, left out
};

/// Builds the model. Errors: fewer than 3 points, non-finite coordinates, normals given for
/// only some points.
Expected<PointModelOutcome> part_model_from_points(const PointCloud& cloud,
                                                   const PointModelSettings& settings = {});

}  // namespace springscan::analysis
