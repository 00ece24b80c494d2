#pragma once
// Deterministic parallel loops for the analysis stages (STYLE.md §3): work is cut into blocks of
// a fixed size that does not depend on the thread count, each block writes its own partial
// result, and partials are combined in block order. A result therefore never depends on how
// many threads ran, only on the input.

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstddef>
#include <thread>
#include <vector>

#include "analysis/point_cloud.hpp"

namespace springscan::analysis {

/// Points per block of a parallel loop. Fixed so that block partials (and so results) are the
/// same for every thread count.
inline constexpr std::size_t kParallelBlock = 4096;

/// The thread count to use: `requested` when > 0, otherwise every hardware thread.
inline int resolve_threads(int requested) {
  if (requested > 0) return requested;
  const unsigned hw = std::thread::hardware_concurrency();
  return hw == 0 ? 1 : static_cast<int>(hw);
}

/// Number of blocks `parallel_blocks` cuts n items into.
inline std::size_t block_count(std::size_t n) { return (n + kParallelBlock - 1) / kParallelBlock; }

/// Calls fn(block, begin, end) once for every block of [0, n), from up to `threads` threads
/// (0 = all cores). fn must only write state owned by its block. Returns after all blocks ran.
template <typename Fn>
void parallel_blocks(std::size_t n, int threads, Fn&& fn) {
  const std::size_t blocks = block_count(n);
  const std::size_t workers =
      std::min<std::size_t>(static_cast<std::size_t>(resolve_threads(threads)), blocks);
  std::atomic<std::size_t> next{0};
  auto work = [&] {
    for (std::size_t b = next++; b < blocks; b = next++) {
      fn(b, b * kParallelBlock, std::min(n, (b + 1) * kParallelBlock));
    }
  };
  if (workers <= 1) {
    work();
    return;
  }
  std::vector<std::thread> pool;
  pool.reserve(workers - 1);
  for (std::size_t t = 1; t < workers; ++t) pool.emplace_back(work);
  work();
  for (auto& thread : pool) thread.join();
}

/// Calls fn(i) for every task i in [0, count) from up to `threads` threads (0 = all cores); for a
/// few coarse tasks whose results go to separate slots (e.g. one ICP per candidate).
template <typename Fn>
void parallel_tasks(std::size_t count, int threads, Fn&& fn) {
  const std::size_t workers =
      std::min<std::size_t>(static_cast<std::size_t>(resolve_threads(threads)), count);
  std::atomic<std::size_t> next{0};
  auto work = [&] {
    for (std::size_t i = next++; i < count; i = next++) fn(i);
  };
  if (workers <= 1) {
    work();
    return;
  }
  std::vector<std::thread> pool;
  pool.reserve(workers - 1);
  for (std::size_t t = 1; t < workers; ++t) pool.emplace_back(work);
  work();
  for (auto& thread : pool) thread.join();
}

/// True when every coordinate is finite.
inline bool all_finite(const std::vector<Vec3>& points) {
  return std::all_of(points.begin(), points.end(), [](const Vec3& p) { return p.allFinite(); });
}

}  // namespace springscan::analysis
