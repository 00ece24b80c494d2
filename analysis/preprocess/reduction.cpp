#include "analysis/preprocess/reduction.hpp"

#include <algorithm>
#include <string>

#include "analysis/core/parallel.hpp"

namespace springscan::analysis {
namespace {

std::vector<Vec3> pick(const std::vector<Vec3>& points, const std::vector<std::uint32_t>& which) {
  std::vector<Vec3> out;
  out.reserve(which.size());
  for (auto i : which) out.push_back(points[i]);
  return out;
}

// Keeps the voxels holding at least `fill` times the median voxel count (at least 1 point).
PointCloud drop_sparse_voxels(const VoxelResult& voxels, double fill, std::size_t& dropped) {
  std::vector<std::uint32_t> counts = voxels.counts;
  if (counts.empty() || !(fill > 0.0)) return voxels.cloud;
  const auto mid = counts.begin() + static_cast<std::ptrdiff_t>(counts.size() / 2);
  std::nth_element(counts.begin(), mid, counts.end());
  const double min_count = std::max(1.0, fill * static_cast<double>(*mid));
  std::vector<std::uint32_t> keep;
  keep.reserve(voxels.counts.size());
  for (std::size_t i = 0; i < voxels.counts.size(); ++i)
    if (static_cast<double>(voxels.counts[i]) >= min_count)
      keep.push_back(static_cast<std::uint32_t>(i));
  dropped = voxels.counts.size() - keep.size();
  return select(voxels.cloud, keep);
}

}  // namespace

std::pair<Vec3, Vec3> bounding_box(const std::vector<Vec3>& points) {
  if (points.empty()) return {Vec3::Zero(), Vec3::Zero()};
  // Block partials on all cores: min and max are exact in any order (a 1M scan's box is taken
  // by several stages).
  std::vector<std::pair<Vec3, Vec3>> partial(block_count(points.size()));
  parallel_blocks(points.size(), 0, [&](std::size_t b, std::size_t begin, std::size_t end) {
    Vec3 lo = points[begin], hi = points[begin];
    for (std::size_t i = begin + 1; i < end; ++i) {
      lo = lo.cwiseMin(points[i]);
      hi = hi.cwiseMax(points[i]);
    }
    partial[b] = {lo, hi};
  });
  Vec3 lo = partial.front().first, hi = partial.front().second;
  for (const auto& [l, h] : partial) {
    lo = lo.cwiseMin(l);
    hi = hi.cwiseMax(h);
  }
  return {lo, hi};
}

Expected<ReductionOutcome> reduce(const PointCloud& scan, const PointCloud& model_samples,
                                  const ReductionSettings& settings) {
  if (scan.empty()) return fail("reduce: the scan is empty");
  if (model_samples.empty()) return fail("reduce: the model has no samples");
  if (!(settings.voxel_size_mm >= 0.0))
    return fail("reduce: voxel_size_mm must be >= 0, got " +
                std::to_string(settings.voxel_size_mm));
  ReductionOutcome out;
  const auto [lo, hi] = bounding_box(scan.points);
  out.voxel_size_mm = settings.voxel_size_mm > 0.0
                          ? settings.voxel_size_mm
                          : (hi - lo).norm() / std::max(settings.auto_voxel_divisions, 1.0);
  if (!(out.voxel_size_mm > 0.0)) out.voxel_size_mm = 1.0;  // all scan points coincide
  // Voxel centroids: one fit point per occupied cell, noise averaged, density evened out.
  auto voxels = voxel_reduce(scan, {out.voxel_size_mm});
  if (!voxels) return voxels.error().prepend("reduce: scan ");
  out.scan_for_fit =
      drop_sparse_voxels(*voxels, settings.min_voxel_fill, out.sparse_voxels_dropped);
  // Paper §2: k-center with the same threshold w on both sets gives similar distributions.
  auto model_kc = kcenter_reduce(model_samples.points, settings.kcenter);
  if (!model_kc) return model_kc.error().prepend("reduce: model ");
  auto scan_kc = kcenter_reduce(out.scan_for_fit.points, settings.kcenter);
  if (!scan_kc) return scan_kc.error().prepend("reduce: scan ");
  out.model_centers = pick(model_samples.points, model_kc->centers);
  out.scan_centers = pick(out.scan_for_fit.points, scan_kc->centers);
  out.model_covering_radius_mm = model_kc->covering_radius_mm;
  out.scan_covering_radius_mm = scan_kc->covering_radius_mm;
  return out;
}

}  // namespace springscan::analysis
