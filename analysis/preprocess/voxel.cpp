#include "analysis/preprocess/voxel.hpp"

#include <bit>
#include <cmath>
#include <string>

#include "analysis/core/parallel.hpp"

namespace springscan::analysis {
namespace {

constexpr std::int64_t kAxisCells = std::int64_t{1} << 20;  // 21 bits per axis in the key

// Open addressing with linear probing: voxel key -> output slot. Sized to a power of two at
// least twice the input, so it never fills up.
class VoxelTable {
 public:
  explicit VoxelTable(std::size_t n) : mask_(std::bit_ceil(2 * n + 2) - 1) {
    keys_.assign(mask_ + 1, kEmpty);
    slots_.assign(mask_ + 1, 0);
  }
  // The slot of `key`, or `fresh` (recorded) when the key is new.
  std::uint32_t find_or_insert(std::uint64_t key, std::uint32_t fresh, bool& inserted) {
    std::size_t h = static_cast<std::size_t>((key * 0x9E3779B97F4A7C15ull) >> 20) & mask_;
    while (keys_[h] != kEmpty) {
      if (keys_[h] == key) {
        inserted = false;
        return slots_[h];
      }
      h = (h + 1) & mask_;
    }
    keys_[h] = key;
    slots_[h] = fresh;
    inserted = true;
    return fresh;
  }

 private:
  static constexpr std::uint64_t kEmpty = ~std::uint64_t{0};
  std::size_t mask_;
  std::vector<std::uint64_t> keys_;
  std::vector<std::uint32_t> slots_;
};

}  // namespace

Expected<VoxelResult> voxel_reduce(const PointCloud& cloud, const VoxelSettings& settings) {
  if (!(settings.voxel_size_mm > 0.0) || !std::isfinite(settings.voxel_size_mm))
    return fail("voxel: voxel_size_mm must be > 0, got " + std::to_string(settings.voxel_size_mm));
  if (!all_finite(cloud.points)) return fail("voxel: input has non-finite (NaN/inf) coordinates");
  VoxelResult result;
  if (cloud.empty()) return result;
  Vec3 lo = cloud.points[0];
  Vec3 hi = lo;
  for (const auto& p : cloud.points) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  const double inv = 1.0 / settings.voxel_size_mm;
  if (((hi - lo) * inv).maxCoeff() >= static_cast<double>(kAxisCells - 1))
    return fail("voxel: voxel_size_mm " + std::to_string(settings.voxel_size_mm) +
                " is too small for a cloud spanning " + std::to_string((hi - lo).maxCoeff()) +
                " mm");
  const bool normals = cloud.has_normals() && cloud.normals.size() == cloud.size();
  VoxelTable table(cloud.size());
  std::vector<Vec3> sums, normal_sums;
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const Vec3 cell = ((cloud.points[i] - lo) * inv).array().floor();
    const auto key = static_cast<std::uint64_t>(cell.x()) |
                     (static_cast<std::uint64_t>(cell.y()) << 21) |
                     (static_cast<std::uint64_t>(cell.z()) << 42);
    bool inserted = false;
    const std::uint32_t slot =
        table.find_or_insert(key, static_cast<std::uint32_t>(sums.size()), inserted);
    if (inserted) {
      sums.push_back(Vec3::Zero());
      result.counts.push_back(0);
      if (normals) normal_sums.push_back(Vec3::Zero());
    }
    sums[slot] += cloud.points[i];
    ++result.counts[slot];
    if (normals) normal_sums[slot] += cloud.normals[i];
  }
  result.cloud.points.resize(sums.size());
  for (std::size_t s = 0; s < sums.size(); ++s)
    result.cloud.points[s] = sums[s] / static_cast<double>(result.counts[s]);
  if (normals) {
    result.cloud.normals.resize(sums.size());
    for (std::size_t s = 0; s < sums.size(); ++s) {
      const double norm = normal_sums[s].norm();
      result.cloud.normals[s] = norm > 0.0 ? Vec3(normal_sums[s] / norm) : Vec3::Zero();
    }
  }
  return result;
}

}  // namespace springscan::analysis
