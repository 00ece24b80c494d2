#include "analysis/preprocess/voxel.hpp"

#include <cmath>
#include <string>
#include <vector>

#include "analysis/core/parallel.hpp"
#include "analysis/preprocess/reduction.hpp"

namespace springscan::analysis {
namespace {

constexpr std::int64_t kAxisCells = std::int64_t{1} << 20;  // 21 bits per axis in the key

// Open addressing with linear probing: voxel key -> output slot. Starts small and doubles
// whenever it is half full: a scan has far fewer voxels than points (a few thousand fit points
// of a 1M scan), and a table sized to the points (2M slots, 24 MB) missed the cache on every
// point, however the points came. The slots, and so the output, are the same at any size.
class VoxelTable {
 public:
  VoxelTable() { resize(kInitialSlots); }
  // The slot of `key`, or `fresh` (recorded) when the key is new.
  std::uint32_t find_or_insert(std::uint64_t key, std::uint32_t fresh, bool& inserted) {
    std::size_t h = probe(key);
    if (keys_[h] == key) {
      inserted = false;
      return slots_[h];
    }
    keys_[h] = key;
    slots_[h] = fresh;
    inserted = true;
    if (++used_ * 2 > keys_.size()) grow();
    return fresh;
  }

 private:
  static constexpr std::uint64_t kEmpty = ~std::uint64_t{0};
  static constexpr std::size_t kInitialSlots = 4096;

  // The position of `key`, or the empty one where it goes.
  std::size_t probe(std::uint64_t key) const {
    std::size_t h = static_cast<std::size_t>((key * 0x9E3779B97F4A7C15ull) >> 20) & mask_;
    while (keys_[h] != kEmpty && keys_[h] != key) h = (h + 1) & mask_;
    return h;
  }
  void resize(std::size_t slots) {
    mask_ = slots - 1;
    keys_.assign(slots, kEmpty);
    slots_.assign(slots, 0);
  }
  void grow() {
    const std::vector<std::uint64_t> keys = std::move(keys_);
    const std::vector<std::uint32_t> slots = std::move(slots_);
    resize(2 * keys.size());
    for (std::size_t i = 0; i < keys.size(); ++i)
      if (keys[i] != kEmpty) {
        const std::size_t h = probe(keys[i]);
        keys_[h] = keys[i];
        slots_[h] = slots[i];
      }
  }

  std::size_t mask_ = 0;
  std::size_t used_ = 0;
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
  const std::pair<Vec3, Vec3> bounds = bounding_box(cloud.points);  // (clang: no captured bindings)
  const Vec3 lo = bounds.first, hi = bounds.second;
  const double inv = 1.0 / settings.voxel_size_mm;
  if (((hi - lo) * inv).maxCoeff() >= static_cast<double>(kAxisCells - 1))
    return fail("voxel: voxel_size_mm " + std::to_string(settings.voxel_size_mm) +
                " is too small for a cloud spanning " + std::to_string((hi - lo).maxCoeff()) +
                " mm");
  // Each point's voxel key on all cores (p - lo >= 0, so truncation is floor, and inline); the
  // table and the sums stay one pass in point order, so that every voxel's sum is taken in the
  // same order as before and its centroid does not change in the last bit.
  std::vector<std::uint64_t> keys(cloud.size());
  parallel_blocks(cloud.size(), 0, [&](std::size_t, std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      const Vec3 cell = (cloud.points[i] - lo) * inv;
      keys[i] = static_cast<std::uint64_t>(cell.x()) |
                (static_cast<std::uint64_t>(cell.y()) << 21) |
                (static_cast<std::uint64_t>(cell.z()) << 42);
    }
  });
  const bool normals = cloud.has_normals() && cloud.normals.size() == cloud.size();
  VoxelTable table;
  std::vector<Vec3> sums, normal_sums;
  std::uint64_t last_key = ~std::uint64_t{0};  // a scan in any spatial order repeats its voxel
  std::uint32_t slot = 0;
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    if (keys[i] != last_key) {
      bool inserted = false;
      slot = table.find_or_insert(keys[i], static_cast<std::uint32_t>(sums.size()), inserted);
      last_key = keys[i];
      if (inserted) {
        sums.push_back(Vec3::Zero());
        result.counts.push_back(0);
        if (normals) normal_sums.push_back(Vec3::Zero());
      }
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
