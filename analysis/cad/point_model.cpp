#include "analysis/cad/point_model.hpp"

#include <string>

#include "analysis/core/parallel.hpp"

namespace springscan::analysis {

Expected<PointModelOutcome> part_model_from_points(const PointCloud& cloud,
                                                   const PointModelSettings& settings) {
  if (cloud.size() < 3)
    return fail("model: needs at least 3 points, got " + std::to_string(cloud.size()));
  if (!all_finite(cloud.points)) return fail("model: non-finite (NaN/inf) coordinates");
  if (!cloud.attributes_consistent())
    return fail("model: " + std::to_string(cloud.normals.size()) + " normals for " +
                std::to_string(cloud.size()) + " points");
  PointModelOutcome out;
  std::vector<Vec3> normals = cloud.normals;
  if (normals.empty()) {
    auto estimated = estimate_normals(cloud.points, settings.normals);
    if (!estimated) return estimated.error().prepend("model: ");
    normals = std::move(estimated->normals);
    out.normals_estimated = true;
  }
  PointCloud& samples = out.model.samples;
  samples.points.reserve(cloud.size());
  samples.normals.reserve(cloud.size());
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const double length = normals[i].norm();
    if (!(length > 0.0) || !std::isfinite(length)) {
      ++out.dropped;
      continue;
    }
    samples.points.push_back(cloud.points[i]);
    samples.normals.push_back(normals[i] / length);
  }
  if (samples.size() < 3) return fail("model: fewer than 3 points have a usable normal");
  return out;
}

}  // namespace springscan::analysis
