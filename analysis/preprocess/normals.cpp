#include "analysis/preprocess/normals.hpp"

#include <Eigen/Eigenvalues>

#include "analysis/core/parallel.hpp"

namespace springscan::analysis {
namespace {

// The neighbourhood of point i as indices into the tree, by k or by radius (paper §2: "a fixed
// number of nearest neighbors or ... the radius of a sphere around the point").
std::size_t neighbourhood(const KdTree& tree, std::size_t i, const NormalSettings& settings,
                          std::vector<std::uint32_t>& indices, std::vector<double>& d2,
                          std::vector<Neighbor>& scratch) {
  const Vec3& p = tree.points()[i];
  if (settings.radius_mm > 0.0) {
    tree.radius(p, settings.radius_mm, scratch);
    indices.resize(scratch.size());
    for (std::size_t j = 0; j < scratch.size(); ++j) indices[j] = scratch[j].index;
    return scratch.size();
  }
  const auto k = static_cast<std::size_t>(std::max(settings.k_neighbors, 1));
  indices.resize(k);
  d2.resize(k);
  return tree.knn(p, k, indices.data(), d2.data());
}

}  // namespace

bool fit_plane(const std::vector<Vec3>& points, const std::uint32_t* indices, std::size_t count,
               Vec3& normal, double& surface_variation) {
  if (count < 3) return false;
  // Centre first: the covariance of raw coordinates (hundreds of mm) loses digits.
  Vec3 mean = Vec3::Zero();
  for (std::size_t j = 0; j < count; ++j) mean += points[indices[j]];
  mean /= static_cast<double>(count);
  Mat3 cov = Mat3::Zero();
  for (std::size_t j = 0; j < count; ++j) {
    const Vec3 d = points[indices[j]] - mean;
    cov.noalias() += d * d.transpose();
  }
  Eigen::SelfAdjointEigenSolver<Mat3> solver;
  solver.computeDirect(cov);
  const Vec3 lambda = solver.eigenvalues().cwiseMax(0.0);  // ascending
  const double sum = lambda.sum();
  normal = solver.eigenvectors().col(0).normalized();
  surface_variation = sum > 0.0 ? lambda(0) / sum : 0.0;
  return normal.allFinite();
}

NormalResult estimate_normals(const KdTree& tree, const NormalSettings& settings) {
  const std::size_t n = tree.size();
  NormalResult result;
  result.normals.assign(n, Vec3::Zero());
  result.surface_variation.assign(n, 0.0);
  std::vector<std::size_t> undefined(block_count(n), 0);
  const auto min_count = static_cast<std::size_t>(std::max(settings.min_neighbors, 3));
  parallel_blocks(n, settings.threads, [&](std::size_t block, std::size_t begin, std::size_t end) {
    std::vector<std::uint32_t> indices;
    std::vector<double> d2;
    std::vector<Neighbor> scratch;
    for (std::size_t i = begin; i < end; ++i) {
      const std::size_t count = neighbourhood(tree, i, settings, indices, d2, scratch);
      Vec3 normal;
      double variation = 0.0;
      if (count < min_count ||
          !fit_plane(tree.points(), indices.data(), count, normal, variation)) {
        ++undefined[block];
        continue;
      }
      if (settings.orient_to_viewpoint && normal.dot(settings.viewpoint - tree.points()[i]) < 0.0)
        normal = -normal;
      result.normals[i] = normal;
      result.surface_variation[i] = variation;
    }
  });
  for (std::size_t u : undefined) result.undefined += u;
  return result;
}

Expected<NormalResult> estimate_normals(const std::vector<Vec3>& points,
                                        const NormalSettings& settings) {
  if (!all_finite(points)) return fail("normals: input has non-finite (NaN/inf) coordinates");
  if (settings.radius_mm <= 0.0 && settings.k_neighbors < 3)
    return fail("normals: k_neighbors must be >= 3, got " + std::to_string(settings.k_neighbors));
  return estimate_normals(KdTree(points), settings);
}

void orient_along_reference(const std::vector<Vec3>& points, std::vector<Vec3>& normals,
                            const KdTree& reference_tree,
                            const std::vector<Vec3>& reference_normals, int threads) {
  if (reference_tree.empty() || reference_normals.size() != reference_tree.size()) return;
  parallel_blocks(points.size(), threads, [&](std::size_t, std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end && i < normals.size(); ++i) {
      const auto hit = reference_tree.nearest(points[i]);
      if (hit && normals[i].dot(reference_normals[hit->index]) < 0.0) normals[i] = -normals[i];
    }
  });
}

}  // namespace springscan::analysis
