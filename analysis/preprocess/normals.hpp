#pragma once
// Normal estimation (paper §2): the normal of a point is the normal of the least-squares plane
// of its neighbourhood, given either by the k nearest neighbours or by a radius.

#include <cstddef>
#include <vector>

#include "analysis/core/expected.hpp"
#include "analysis/core/kdtree.hpp"
#include "analysis/core/point_cloud.hpp"

namespace springscan::analysis {

struct NormalSettings {
  int k_neighbors = 10;             ///< neighbourhood size (the point itself included); paper: 10
  double radius_mm = 0.0;           ///< > 0: use every point within this radius instead of k
  int min_neighbors = 3;            ///< fewer neighbours than this: no plane, normal left at zero
  bool orient_to_viewpoint = true;  ///< flip each normal to face `viewpoint`
  Vec3 viewpoint = Vec3(0.0, 0.0, 1e6);  ///< mm; the default looks down from far above +z
  int threads = 0;                       ///< worker threads, 0 = all cores
};

struct NormalResult {
  std::vector<Vec3> normals;              ///< unit normals; zero where the plane was undefined
  std::vector<double> surface_variation;  ///< lambda_min / (sum of lambdas), 0 (plane) .. 1/3
  std::size_t undefined = 0;              ///< points with too few neighbours (normal zero)
};

/// The least-squares plane normal of every point of `tree` (its own points). Thread-safe: the
/// tree is only read. O(n k log n).
NormalResult estimate_normals(const KdTree& tree, const NormalSettings& settings = {});

/// The same, building the tree itself. Errors: non-finite coordinates, bad settings.
Expected<NormalResult> estimate_normals(const std::vector<Vec3>& points,
                                        const NormalSettings& settings = {});

/// Flips each of `normals` (of `points`) to agree with the normal of the nearest point of
/// `reference` (e.g. CAD samples, already in the same frame). Needs reference normals.
void orient_along_reference(const std::vector<Vec3>& points, std::vector<Vec3>& normals,
                            const KdTree& reference_tree,
                            const std::vector<Vec3>& reference_normals, int threads = 0);

/// The least-squares plane of `points[indices]`: unit normal and surface variation. Returns
/// false when fewer than 3 points are given.
bool fit_plane(const std::vector<Vec3>& points, const std::uint32_t* indices, std::size_t count,
               Vec3& normal, double& surface_variation);

}  // namespace springscan::analysis
