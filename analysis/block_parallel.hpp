#pragma once
// Deterministic parallel loops (HELPERS.md "Threads"): the range is cut into fixed-size blocks
// that do not depend on the thread count, workers take blocks in turn, and callers keep one
// partial result per block and combine them in block order. Results are therefore identical
// for any thread count.

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <thread>
#include <vector>

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

}  // namespace springscan::analysis
