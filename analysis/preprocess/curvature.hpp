#pragma once
// The paper's curvature measure C(p) and the reduction by minC (paper §2, Figure 2).
//
// Reading of the printed formula (see docs/method.md): C(p) = 1/m * sum_i |n . q_i|, with n the
// unit normal of p and q_i the unit vector from p to its i-th neighbour. It is the mean sine of
// the angle at which the neighbours leave the tangent plane: 0 on a plane, and about
// d / (2 R) on a sphere of radius R sampled at spacing d, so it rises as R falls.

#include <cstddef>
#include <cstdint>
#include <vector>

#include "analysis/core/expected.hpp"
#include "analysis/core/kdtree.hpp"
#include "analysis/core/point_cloud.hpp"

namespace springscan::analysis {

struct CurvatureSettings {
  int k_neighbors = 10;    ///< m, the neighbourhood size (the point itself excluded); paper: 10
  double radius_mm = 0.0;  ///< > 0: every neighbour within this radius instead of k
  double min_curvature = 0.015;         ///< minC: points with C < minC are removed (paper: 0.015)
  double base_kcenter_radius_mm = 0.0;  ///< > 0: also keep a k-center sample at this w, so
                                        ///< flat areas and boundaries keep points (paper §2)
  int threads = 0;                      ///< worker threads, 0 = all cores
};

/// C(p) of every point of `tree` with the given unit normals (one per point). Points with fewer
/// than 3 neighbours get C = 0. Thread-safe; O(n m log n).
std::vector<double> curvature_measure(const KdTree& tree, const std::vector<Vec3>& normals,
                                      const CurvatureSettings& settings = {});

struct CurvatureReduction {
  std::vector<double> curvature;      ///< C(p) per input point
  std::vector<std::uint32_t> kept;    ///< ascending indices of the points kept
  std::size_t kept_by_curvature = 0;  ///< of those, with C >= minC
};

/// Keeps the points with C >= minC (plus the k-center base sample when asked).
/// Errors: normals missing or non-finite points, settings out of range.
Expected<CurvatureReduction> reduce_by_curvature(const PointCloud& cloud,
                                                 const CurvatureSettings& settings = {});

}  // namespace springscan::analysis
