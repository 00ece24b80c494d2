#include "analysis/core/spatial_order.hpp"

#include <algorithm>
#include <array>
#include <numeric>

#include "analysis/core/parallel.hpp"

namespace springscan::analysis {
namespace {

constexpr int kDigitBits = kSpatialOrderBits;  // three passes
constexpr std::size_t kDigits = std::size_t{1} << kDigitBits;
constexpr std::uint32_t kAxisMax = (1u << kSpatialOrderBits) - 1;

struct Keyed {
  std::uint32_t key;
  std::uint32_t index;
};

// The low 10 bits of v, bit i moved to bit 3i (the usual Morton spread).
std::uint32_t spread(std::uint32_t v) {
  v &= 0x3ffu;
  v = (v | (v << 16)) & 0x030000ffu;
  v = (v | (v << 8)) & 0x0300f00fu;
  v = (v | (v << 4)) & 0x030c30c3u;
  v = (v | (v << 2)) & 0x09249249u;
  return v;
}

// The bounding box, from per-block partials (combined in block order).
std::pair<Vec3, Vec3> box(const std::vector<Vec3>& points, int threads) {
  std::vector<std::pair<Vec3, Vec3>> partial(block_count(points.size()));
  parallel_blocks(points.size(), threads, [&](std::size_t b, std::size_t begin, std::size_t end) {
    Vec3 lo = points[begin], hi = points[begin];
    for (std::size_t i = begin + 1; i < end; ++i) {
      lo = lo.cwiseMin(points[i]);
      hi = hi.cwiseMax(points[i]);
    }
    partial[b] = {lo, hi};
  });
  auto [lo, hi] = partial.front();
  for (const auto& [l, h] : partial) {
    lo = lo.cwiseMin(l);
    hi = hi.cwiseMax(h);
  }
  return {lo, hi};
}

// One stable counting-sort pass of `from` into `to` by the digit at `shift`: per-block
// histograms, each (digit, block) pair's start by a prefix sum in digit-then-block order, then
// each block scatters its points in input order. False (nothing moved) when every key has the
// same digit there.
bool radix_pass(const std::vector<Keyed>& from, std::vector<Keyed>& to, int shift, int threads) {
  const std::size_t blocks = block_count(from.size());
  std::vector<std::array<std::uint32_t, kDigits>> start(blocks);
  const auto digit = [shift](const Keyed& k) { return (k.key >> shift) & (kDigits - 1); };
  parallel_blocks(from.size(), threads, [&](std::size_t b, std::size_t begin, std::size_t end) {
    start[b].fill(0);
    for (std::size_t i = begin; i < end; ++i) ++start[b][digit(from[i])];
  });
  for (std::size_t d = 0; d < kDigits; ++d) {
    std::size_t total = 0;
    for (std::size_t b = 0; b < blocks; ++b) total += start[b][d];
    if (total == from.size()) return false;
  }
  std::uint32_t running = 0;  // the caller's points fit 32-bit indices
  for (std::size_t d = 0; d < kDigits; ++d)
    for (std::size_t b = 0; b < blocks; ++b) {
      const std::uint32_t count = start[b][d];
      start[b][d] = running;
      running += count;
    }
  parallel_blocks(from.size(), threads, [&](std::size_t b, std::size_t begin, std::size_t end) {
    std::array<std::uint32_t, kDigits>& next = start[b];
    for (std::size_t i = begin; i < end; ++i) to[next[digit(from[i])]++] = from[i];
  });
  return true;
}

// The points keyed by the Morton code of their cell, sorted stably by it.
std::vector<Keyed> morton_sorted(const std::vector<Vec3>& points, int threads) {
  const std::pair<Vec3, Vec3> bounds = box(points, threads);  // (clang: no captured bindings)
  const Vec3 lo = bounds.first, hi = bounds.second;
  const double extent = (hi - lo).maxCoeff();
  const double scale = extent > 0.0 ? double(kAxisMax + 1) / extent : 0.0;
  std::vector<Keyed> keyed(points.size()), other(points.size());
  parallel_blocks(points.size(), threads, [&](std::size_t, std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      const Vec3 cell = ((points[i] - lo) * scale).cwiseMin(double(kAxisMax));
      keyed[i] = {spread(static_cast<std::uint32_t>(cell.x())) |
                      (spread(static_cast<std::uint32_t>(cell.y())) << 1) |
                      (spread(static_cast<std::uint32_t>(cell.z())) << 2),
                  static_cast<std::uint32_t>(i)};
    }
  });
  for (int shift = 0; shift < 3 * kSpatialOrderBits; shift += kDigitBits)
    if (radix_pass(keyed, other, shift, threads)) keyed.swap(other);
  return keyed;
}

std::vector<std::uint32_t> indices_of(const std::vector<Keyed>& keyed, int threads) {
  std::vector<std::uint32_t> order(keyed.size());
  parallel_blocks(keyed.size(), threads, [&](std::size_t, std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) order[i] = keyed[i].index;
  });
  return order;
}

// canonical_order, and the points in that order when `with_points`.
OrderedPoints canonical(const std::vector<Vec3>& points, int threads, bool with_points) {
  if (points.empty()) return {};
  const std::vector<Keyed> keyed = morton_sorted(points, threads);
  // The points copied in cell order, so that sorting a cell reads neighbouring memory (its
  // points' coordinates read through their input indices missed the cache on every compare).
  struct Entry {
    Vec3 point;
    std::uint32_t key;
    std::uint32_t index;
  };
  std::vector<Entry> entries(keyed.size());
  parallel_blocks(keyed.size(), threads, [&](std::size_t, std::size_t begin, std::size_t end) {
    for (std::size_t k = begin; k < end; ++k)
      entries[k] = {points[keyed[k].index], keyed[k].key, keyed[k].index};
  });
  // Within a cell by coordinates; equal points (the same point) by input index, as the stable
  // sort by cell left them.
  const auto by_coordinates = [](const Entry& a, const Entry& b) {
    if (a.point.x() != b.point.x()) return a.point.x() < b.point.x();
    if (a.point.y() != b.point.y()) return a.point.y() < b.point.y();
    if (a.point.z() != b.point.z()) return a.point.z() < b.point.z();
    return a.index < b.index;
  };
  // Each block sorts the cells (runs of one key) that start in it, to their end. The runs are
  // found in `keyed`, which no block writes: a block reading `entries` at its start would read
  // the cell the block before it is sorting (a data race, TSan).
  OrderedPoints out{std::vector<std::uint32_t>(entries.size()), {}};
  if (with_points) out.points.resize(entries.size());
  parallel_blocks(entries.size(), threads, [&](std::size_t, std::size_t begin, std::size_t end) {
    std::size_t run = begin;
    while (run > 0 && run < keyed.size() && keyed[run].key == keyed[run - 1].key) ++run;
    while (run < end) {
      std::size_t next = run + 1;
      while (next < keyed.size() && keyed[next].key == keyed[run].key) ++next;
      const auto first = entries.begin() + static_cast<std::ptrdiff_t>(run);
      std::sort(first, entries.begin() + static_cast<std::ptrdiff_t>(next), by_coordinates);
      for (std::size_t k = run; k < next; ++k) out.order[k] = entries[k].index;
      if (with_points)
        for (std::size_t k = run; k < next; ++k) out.points[k] = entries[k].point;
      run = next;
    }
  });
  return out;
}

}  // namespace

std::vector<std::uint32_t> spatial_order(const std::vector<Vec3>& points, int threads) {
  if (points.empty()) return {};
  return indices_of(morton_sorted(points, threads), threads);
}

std::vector<std::uint32_t> canonical_order(const std::vector<Vec3>& points, int threads) {
  return canonical(points, threads, false).order;
}

OrderedPoints canonically_ordered(const std::vector<Vec3>& points, int threads) {
  return canonical(points, threads, true);
}

bool spatially_coherent(const std::vector<Vec3>& points) {
  constexpr std::size_t kPairs = 1024;
  constexpr double kCoherentShare = 0.01;
  if (points.size() < 2) return true;
  const std::size_t pairs = std::min(kPairs, points.size() - 1);
  const std::size_t stride = (points.size() - 1) / pairs;
  std::vector<double> steps;
  steps.reserve(pairs);
  Vec3 lo = points[0], hi = points[0];
  for (std::size_t k = 0; k < pairs; ++k) {
    const Vec3 &a = points[k * stride], &b = points[k * stride + 1];
    steps.push_back((b - a).norm());
    lo = lo.cwiseMin(a).cwiseMin(b);
    hi = hi.cwiseMax(a).cwiseMax(b);
  }
  const auto mid = steps.begin() + static_cast<std::ptrdiff_t>(steps.size() / 2);
  std::nth_element(steps.begin(), mid, steps.end());
  return *mid <= kCoherentShare * (hi - lo).norm();
}

std::vector<std::uint32_t> search_order(const std::vector<Vec3>& points, int threads) {
  if (!spatially_coherent(points)) return spatial_order(points, threads);
  std::vector<std::uint32_t> identity(points.size());
  std::iota(identity.begin(), identity.end(), 0u);
  return identity;
}

}  // namespace springscan::analysis
