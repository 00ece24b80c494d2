#pragma once
// Voxel reduction: one point per occupied cube of side `voxel_size_mm`, the centroid of the
// points inside it (normals averaged and renormalised, other attributes dropped).
// Deterministic: voxels come out in the order of their first point in the input.

#include <cstddef>
#include <cstdint>
#include <vector>

#include "analysis/core/expected.hpp"
#include "analysis/core/point_cloud.hpp"

namespace springscan::analysis {

struct VoxelSettings {
  double voxel_size_mm = 1.0;  ///< edge of the voxel cube, mm; must be > 0
};

struct VoxelResult {
  PointCloud cloud;                   ///< one centroid per occupied voxel
  std::vector<std::uint32_t> counts;  ///< input points per output point
};

/// O(n) expected (open-addressing hash of voxel keys). Errors: non-finite points, a voxel size
/// <= 0, or a size so small that voxel keys would overflow (more than 2^20 voxels per axis).
Expected<VoxelResult> voxel_reduce(const PointCloud& cloud, const VoxelSettings& settings = {});

}  // namespace springscan::analysis
