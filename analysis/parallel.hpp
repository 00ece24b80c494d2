#pragma once
// The fitting stages' use of analysis/block_parallel.hpp: one fixed block size for point loops
// (so block partials, and therefore results, never depend on the thread count), coarse tasks,
// and the finiteness check every stage runs on its input.

#include <algorithm>
#include <cstddef>
#include <vector>

#include "analysis/block_parallel.hpp"
#include "analysis/point_cloud.hpp"

namespace springscan::analysis {

/// Points per block of a parallel point loop.
inline constexpr std::size_t kParallelBlock = 4096;

/// Number of blocks `parallel_blocks` cuts n points into.
inline std::size_t block_count(std::size_t n) { return block_count(n, kParallelBlock); }

/// Calls fn(block, begin, end) for every kParallelBlock-sized block of [0, n) from up to
/// `threads` threads (0 = all cores). fn must only write state owned by its block.
template <typename Fn>
void parallel_blocks(std::size_t n, int threads, Fn&& fn) {
  for_each_block(n, kParallelBlock, threads, fn);
}

/// Calls fn(i) for every task i in [0, count) from up to `threads` threads: for a few coarse
/// tasks whose results go to separate slots (e.g. one ICP per PCA candidate).
template <typename Fn>
void parallel_tasks(std::size_t count, int threads, Fn&& fn) {
  for_each_block(count, 1, threads, [&](std::size_t task, std::size_t, std::size_t) { fn(task); });
}

/// True when every coordinate is finite.
inline bool all_finite(const std::vector<Vec3>& points) {
  return std::all_of(points.begin(), points.end(), [](const Vec3& p) { return p.allFinite(); });
}

}  // namespace springscan::analysis
