#pragma once
// The fitting stages' use of analysis/block_parallel.hpp: one fixed block size for point loops
// (so block partials, and therefore results, never depend on the thread count), coarse tasks,
// and the finiteness check every stage runs on its input.

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <thread>
#include <vector>

#include "analysis/core/point_cloud.hpp"

namespace springscan::analysis {

/// Number of worker threads for a `threads` setting: 0 means hardware_concurrency.
inline unsigned resolve_threads(int threads) {
  if (threads > 0) return static_cast<unsigned>(threads);
  return std::max(1u, std::thread::hardware_concurrency());
}

/// Number of blocks of `block_size` that cover `count` items.
inline std::size_t block_count(std::size_t count, std::size_t block_size) {
  return (count + block_size - 1) / block_size;
}

/// Calls fn(block, begin, end) once per block of [0, count), on up to `threads` threads
/// (0 = all cores). fn must only write data owned by its block.
template <typename Fn>
void for_each_block(std::size_t count, std::size_t block_size, int threads, Fn&& fn) {
  const std::size_t blocks = block_count(count, block_size);
  const auto run = [&](std::size_t b) {
    fn(b, b * block_size, std::min(count, (b + 1) * block_size));
  };
  const std::size_t workers = std::min<std::size_t>(resolve_threads(threads), blocks);
  if (workers <= 1) {
    for (std::size_t b = 0; b < blocks; ++b) run(b);
    return;
  }
  std::atomic<std::size_t> next{0};
  const auto work = [&] {
    for (std::size_t b = next++; b < blocks; b = next++) run(b);
  };
  std::vector<std::thread> pool;
  pool.reserve(workers - 1);
  for (std::size_t t = 1; t < workers; ++t) pool.emplace_back(work);
  work();
  for (auto& thread : pool) thread.join();
}

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
