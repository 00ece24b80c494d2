#include "analysis/preprocess/curvature.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "analysis/core/parallel.hpp"
#include "analysis/preprocess/kcenter.hpp"

namespace springscan::analysis {
namespace {

// Paper §2: C(p) = 1/m sum n x q_i / (1 + |q_i|). With q_i normalised, |n x q_i| is ~1 on a
// plane, the opposite of a curvature. The component of q_i along n, |n . q_i|, is 0 on a plane
// and grows with curvature; that is the reading used (docs/method.md).
double measure_at(const Vec3& p, const Vec3& n, const std::vector<Vec3>& points,
                  const std::uint32_t* neighbours, std::size_t count) {
  double sum = 0.0;
  std::size_t m = 0;
  for (std::size_t j = 0; j < count; ++j) {
    const Vec3 d = points[neighbours[j]] - p;
    const double length = d.norm();
    if (!(length > 0.0)) continue;  // the point itself, or a duplicate
    sum += std::abs(n.dot(d)) / length;
    ++m;
  }
  return m >= 3 ? sum / static_cast<double>(m) : 0.0;
}

}  // namespace

std::vector<double> curvature_measure(const KdTree& tree, const std::vector<Vec3>& normals,
                                      const CurvatureSettings& settings) {
  const std::size_t n = tree.size();
  std::vector<double> result(n, 0.0);
  if (normals.size() != n) return result;
  parallel_blocks(n, settings.threads, [&](std::size_t, std::size_t begin, std::size_t end) {
    const auto k = static_cast<std::size_t>(std::max(settings.k_neighbors, 1)) + 1;  // + itself
    std::vector<std::uint32_t> indices(k);
    std::vector<double> d2(k);
    std::vector<Neighbor> found;
    for (std::size_t i = begin; i < end; ++i) {
      const Vec3& p = tree.points()[i];
      std::size_t count = 0;
      if (settings.radius_mm > 0.0) {
        tree.radius(p, settings.radius_mm, found);
        indices.resize(std::max(indices.size(), found.size()));
        for (const auto& f : found) indices[count++] = f.index;
      } else {
        count = tree.knn(p, k, indices.data(), d2.data());
      }
      result[i] = measure_at(p, normals[i], tree.points(), indices.data(), count);
    }
  });
  return result;
}

Expected<CurvatureReduction> reduce_by_curvature(const PointCloud& cloud,
                                                 const CurvatureSettings& settings) {
  if (cloud.normals.size() != cloud.size())
    return fail("curvature: needs one normal per point, got " +
                std::to_string(cloud.normals.size()) + " for " + std::to_string(cloud.size()));
  if (!all_finite(cloud.points)) return fail("curvature: input has non-finite coordinates");
  if (settings.radius_mm <= 0.0 && settings.k_neighbors < 3)
    return fail("curvature: k_neighbors must be >= 3, got " + std::to_string(settings.k_neighbors));
  CurvatureReduction result;
  result.curvature = curvature_measure(KdTree(cloud.points), cloud.normals, settings);
  std::vector<char> keep(cloud.size(), 0);
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    if (result.curvature[i] >= settings.min_curvature) {
      keep[i] = 1;
      ++result.kept_by_curvature;
    }
  }
  if (settings.base_kcenter_radius_mm > 0.0) {
    auto base = kcenter_reduce(cloud.points, {0, settings.base_kcenter_radius_mm, 0, 128});
    if (!base) return base.error().prepend("curvature: ");
    for (auto i : base->centers) keep[i] = 1;
  }
  for (std::size_t i = 0; i < cloud.size(); ++i)
    if (keep[i]) result.kept.push_back(static_cast<std::uint32_t>(i));
  return result;
}

}  // namespace springscan::analysis
