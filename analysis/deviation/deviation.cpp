#include "analysis/deviation/deviation.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <string>

#include "analysis/core/parallel.hpp"
#include "analysis/core/spatial_order.hpp"

namespace springscan::analysis {
namespace {

constexpr std::size_t kMaxCellCandidates = 1024;  // beyond: plain KD-tree queries (outliers)
constexpr std::size_t kCellsPerBlock = 64;        // cells per parallel block (fixed)

// Points grouped by a cubic grid: order[offsets[g] .. offsets[g+1]) are cell g's points.
struct CellGrouping {
  std::vector<std::uint32_t> order;
  std::vector<std::size_t> offsets;  // empty: the grid would be too fine for the extent
  std::vector<Vec3> centers;
};

CellGrouping group_by_cell(const std::vector<Vec3>& points, double cell) {
  CellGrouping g;
  Vec3 lo = points[0], hi = points[0];
  for (const auto& p : points) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  if (!(cell > 0.0) || ((hi - lo) / cell).maxCoeff() >= double((1 << 21) - 2)) return g;
  const std::size_t mask = std::bit_ceil(2 * points.size() + 2) - 1;
  std::vector<std::uint64_t> keys(mask + 1, ~std::uint64_t{0});
  std::vector<std::uint32_t> slots(mask + 1, 0), cell_of(points.size());
  std::vector<std::size_t> counts;
  for (std::size_t i = 0; i < points.size(); ++i) {
    const Eigen::Array3d c = ((points[i] - lo) / cell).array().floor();
    const std::uint64_t key = static_cast<std::uint64_t>(c.x()) |
                              (static_cast<std::uint64_t>(c.y()) << 21) |
                              (static_cast<std::uint64_t>(c.z()) << 42);
    std::size_t h = static_cast<std::size_t>((key * 0x9E3779B97F4A7C15ull) >> 20) & mask;
    while (keys[h] != key && keys[h] != ~std::uint64_t{0}) h = (h + 1) & mask;
    if (keys[h] != key) {
      keys[h] = key;
      slots[h] = static_cast<std::uint32_t>(counts.size());
      counts.push_back(0);
      g.centers.push_back(lo + (c.matrix() + Vec3::Constant(0.5)) * cell);
    }
    cell_of[i] = slots[h];
    ++counts[slots[h]];
  }
  g.offsets.assign(counts.size() + 1, 0);
  for (std::size_t c = 0; c < counts.size(); ++c) g.offsets[c + 1] = g.offsets[c] + counts[c];
  std::vector<std::size_t> fill(g.offsets.begin(), g.offsets.end() - 1);
  g.order.resize(points.size());
  for (std::size_t i = 0; i < points.size(); ++i)
    g.order[fill[cell_of[i]]++] = static_cast<std::uint32_t>(i);
  return g;
}

// The median nearest-neighbour distance of up to 256 evenly strided samples, mm.
double median_spacing(const KdTree& tree) {
  std::vector<double> d;
  const std::size_t stride = std::max<std::size_t>(1, tree.size() / 256);
  std::uint32_t index[2];
  double d2[2];
  for (std::size_t i = 0; i < tree.size(); i += stride)
    if (tree.knn(tree.points()[i], 2, index, d2) == 2 && d2[1] > 0.0) d.push_back(std::sqrt(d2[1]));
  if (d.empty()) return 1.0;
  std::nth_element(d.begin(), d.begin() + static_cast<std::ptrdiff_t>(d.size() / 2), d.end());
  return d[d.size() / 2];
}

// Nearest sample by plain KD-tree queries, for points outside the cell scheme.
void nearest_each(const std::vector<Vec3>& q, const std::uint32_t* which, std::size_t count,
                  const KdTree& tree, std::vector<std::uint32_t>& out) {
  for (std::size_t k = 0; k < count; ++k) out[which[k]] = tree.nearest(q[which[k]])->index;
}

// Exact nearest sample of every point of one cell (centre c, half diagonal h): the nearest
// sample of any point q of the cell lies within h + r_c of q (r_c: c's nearest distance), so
// within 2h + r_c of c. One radius query per cell (radius 2h + guard, which holds that bound
// whenever r_c <= guard), then per point a brute force over the candidates sorted by their
// distance to c, cut off once |s - c| - |q - c| exceeds the best distance (triangle
// inequality).
void nearest_in_cell(const std::vector<Vec3>& q, const std::uint32_t* which, std::size_t count,
                     const Vec3& c, double h, double guard, const KdTree& tree,
                     std::vector<Neighbor>& found, std::vector<std::uint32_t>& out) {
  if (count < 4) {  // the radius query would not pay
    nearest_each(q, which, count, tree, out);
    return;
  }
  tree.radius(c, (2.0 * h + guard) * (1.0 + 1e-12) + 1e-9, found);
  if (found.empty() || found.size() > kMaxCellCandidates ||
      std::sqrt(found.front().squared_distance) > guard) {  // far off the surface: outliers
    nearest_each(q, which, count, tree, out);
    return;
  }
  thread_local std::vector<Vec3> candidates;
  thread_local std::vector<double> from_center;
  candidates.clear();
  from_center.clear();
  const double bound = 2.0 * h + std::sqrt(found.front().squared_distance);
  for (const Neighbor& f : found) {
    const double d = std::sqrt(f.squared_distance);
    if (d > bound * (1.0 + 1e-12) + 1e-9) break;
    candidates.push_back(tree.points()[f.index]);
    from_center.push_back(d);
  }
  for (std::size_t k = 0; k < count; ++k) {
    const Vec3 p = q[which[k]];
    const double delta = (p - c).norm();
    double best = std::numeric_limits<double>::infinity(), best_distance = best;
    std::size_t best_j = 0;
    for (std::size_t j = 0; j < candidates.size(); ++j) {
      if (from_center[j] - delta > best_distance * (1.0 + 1e-12) + 1e-12) break;
      const double d2 = (candidates[j] - p).squaredNorm();
      if (d2 < best || (d2 == best && found[j].index < found[best_j].index)) {
        best = d2;
        best_j = j;
        best_distance = std::sqrt(d2);
      }
    }
    out[which[k]] = found[best_j].index;
  }
}

// The value of rank `rank` (0-based) among |d|, the one nth_element puts there, on all cores:
// a non-negative double's bits order as its value does, so a histogram of the leading bits
// (sign, exponent and 3 bits of mantissa: an eighth of an octave) in a few parallel chunks finds
// the bucket that holds the rank, and only that bucket's values, a few percent, are selected
// among. nth_element over all of 1M values took ~10 ms on one thread. Nothing (the caller
// selects among all) when a value is NaN, which has no place in that order.
std::optional<double> magnitude_at_rank(const std::vector<double>& d, std::size_t rank) {
  constexpr int kShift = 49;  // 64 - 1 sign - 11 exponent - 3 mantissa bits
  constexpr std::size_t kBuckets = std::size_t{1} << (64 - kShift);
  constexpr std::size_t kChunks = 8;  // fixed: the counts do not depend on the thread count
  const auto bucket = [](double v) {
    return static_cast<std::size_t>(std::bit_cast<std::uint64_t>(std::abs(v)) >> kShift);
  };
  const std::size_t chunk = (d.size() + kChunks - 1) / kChunks;
  std::vector<std::vector<std::uint32_t>> counts(kChunks);
  std::vector<char> nan(kChunks, 0);
  for_each_block(d.size(), chunk, 0, [&](std::size_t c, std::size_t begin, std::size_t end) {
    counts[c].assign(kBuckets, 0);
    for (std::size_t i = begin; i < end; ++i) {
      if (std::isnan(d[i])) nan[c] = 1;
      ++counts[c][bucket(d[i])];
    }
  });
  if (std::find(nan.begin(), nan.end(), 1) != nan.end()) return std::nullopt;
  std::size_t below = 0, target = 0;
  for (; target < kBuckets; ++target) {
    std::size_t in = 0;
    for (const auto& c : counts)
      if (!c.empty()) in += c[target];
    if (below + in > rank) break;
    below += in;
  }
  std::vector<std::vector<double>> inside(kChunks);
  for_each_block(d.size(), chunk, 0, [&](std::size_t c, std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i)
      if (bucket(d[i]) == target) inside[c].push_back(std::abs(d[i]));
  });
  std::vector<double> values;
  for (const auto& v : inside) values.insert(values.end(), v.begin(), v.end());
  const auto at = values.begin() + static_cast<std::ptrdiff_t>(rank - below);
  std::nth_element(values.begin(), at, values.end());
  return *at;
}

}  // namespace

std::vector<std::uint32_t> nearest_samples(const std::vector<Vec3>& points, const KdTree& tree,
                                           const DeviationSettings& settings) {
  std::vector<std::uint32_t> out(points.size(), 0);
  if (points.empty() || tree.empty()) return out;
  const double spacing = median_spacing(tree);
  const double cell = settings.cell_size_mm > 0.0 ? settings.cell_size_mm : 3.0 * spacing;
  const double guard = 2.0 * spacing;  // scan points farther off the samples: plain queries
  const CellGrouping groups = group_by_cell(points, cell);
  if (groups.offsets.empty()) {  // too fine a grid for the extent: plain queries
    parallel_blocks(points.size(), settings.threads,
                    [&](std::size_t, std::size_t b, std::size_t e) {
                      for (std::size_t i = b; i < e; ++i) out[i] = tree.nearest(points[i])->index;
                    });
    return out;
  }
  const double h = 0.5 * std::sqrt(3.0) * cell;
  const std::size_t cells = groups.offsets.size() - 1;
  for_each_block(cells, kCellsPerBlock, settings.threads,
                 [&](std::size_t, std::size_t begin, std::size_t end) {
                   std::vector<Neighbor> found;
                   for (std::size_t g = begin; g < end; ++g) {
                     const std::uint32_t* which = groups.order.data() + groups.offsets[g];
                     const std::size_t count = groups.offsets[g + 1] - groups.offsets[g];
                     nearest_in_cell(points, which, count, groups.centers[g], h, guard, tree, found,
                                     out);
                   }
                 });
  return out;
}

Expected<DeviationResult> signed_deviation(const std::vector<Vec3>& scan_in_cad,
                                           const PartModel& model, const KdTree& model_tree,
                                           const DeviationSettings& settings) {
  if (!all_finite(scan_in_cad)) return fail("deviation: the scan has non-finite coordinates");
  DeviationResult result;
  result.exact = model.distance != nullptr;
  if (!result.exact) {
    if (model_tree.empty()) return fail("deviation: the model has no samples");
    if (model.samples.normals.size() != model_tree.size())
      return fail("deviation: the model samples need one normal each (" +
                  std::to_string(model.samples.normals.size()) + " normals for " +
                  std::to_string(model_tree.size()) + " indexed samples)");
  }
  result.signed_distance_mm.resize(scan_in_cad.size());
  if (result.exact) {
    // In space order, whatever order the scan came in: the previous point's foot bounds the
    // next point's distance, and that bound prunes the search (SurfaceDistance::closest_within),
    // and neighbouring queries share the BVH nodes in cache. Each point's answer is the same in
    // any order. A shuffled scan's blocks are gathered in space order first and their answers
    // scattered after, in tight loops whose cache misses overlap (inside the search loop each
    // would stall it); a scan in scanner lines is in such an order already.
    const bool coherent = spatially_coherent(scan_in_cad);
    const std::vector<std::uint32_t> order =
        coherent ? std::vector<std::uint32_t>{} : spatial_order(scan_in_cad, settings.threads);
    parallel_blocks(
        scan_in_cad.size(), settings.threads, [&](std::size_t, std::size_t begin, std::size_t end) {
          if (coherent) {
            closest_in_order(
                *model.distance, begin, end, [&](std::size_t i) { return scan_in_cad[i]; },
                [&](std::size_t i, const SurfaceHit& hit) {
                  result.signed_distance_mm[i] = hit.signed_distance_mm;
                });
            return;
          }
          std::vector<Vec3> points(end - begin);
          std::vector<double> distances(end - begin);
          for (std::size_t k = begin; k < end; ++k) points[k - begin] = scan_in_cad[order[k]];
          closest_in_order(
              *model.distance, 0, points.size(), [&](std::size_t j) { return points[j]; },
              [&](std::size_t j, const SurfaceHit& hit) { distances[j] = hit.signed_distance_mm; });
          for (std::size_t k = begin; k < end; ++k)
            result.signed_distance_mm[order[k]] = distances[k - begin];
        });
  } else {
    // Tangent plane of the nearest sample: exact on flat faces, and the sign says whether the
    // point lies above or below the surface (paper §3, Figure 7 colouring).
    const auto nearest = nearest_samples(scan_in_cad, model_tree, settings);
    for (std::size_t i = 0; i < scan_in_cad.size(); ++i) {
      const std::uint32_t j = nearest[i];
      result.signed_distance_mm[i] =
          model.samples.normals[j].dot(scan_in_cad[i] - model_tree.points()[j]);
    }
  }
  result.statistics = deviation_statistics(result.signed_distance_mm);
  return result;
}

DeviationStatistics deviation_statistics(const std::vector<double>& d) {
  DeviationStatistics s;
  s.points = d.size();
  if (d.empty()) return s;
  struct Sums {
    double sum = 0.0, sum2 = 0.0;
  };
  std::vector<Sums> partial(block_count(d.size()));
  parallel_blocks(d.size(), 0, [&](std::size_t b, std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      partial[b].sum += d[i];
      partial[b].sum2 += d[i] * d[i];
    }
  });
  Sums total;
  for (const auto& p : partial) {  // block order: independent of the thread count
    total.sum += p.sum;
    total.sum2 += p.sum2;
  }
  const auto [lo, hi] = std::minmax_element(d.begin(), d.end());
  s.min_mm = *lo;
  s.max_mm = *hi;
  const auto n = static_cast<double>(d.size());
  s.mean_mm = total.sum / n;
  s.rms_mm = std::sqrt(total.sum2 / n);
  // Nearest rank: the smallest value with at least 95 % of the values at or below it.
  const auto rank = static_cast<std::size_t>(std::ceil(0.95 * n)) - 1;
  if (const auto p95 = magnitude_at_rank(d, rank)) {
    s.p95_mm = *p95;
    return s;
  }
  std::vector<double> magnitude(d.size());
  std::transform(d.begin(), d.end(), magnitude.begin(), [](double v) { return std::abs(v); });
  std::nth_element(magnitude.begin(), magnitude.begin() + static_cast<std::ptrdiff_t>(rank),
                   magnitude.end());
  s.p95_mm = magnitude[rank];
  return s;
}

double trimmed_rms(std::vector<double> values, double trimmed_fraction) {
  if (values.empty()) return 0.0;
  for (double& v : values) v = v * v;
  const auto drop = static_cast<std::size_t>(std::clamp(trimmed_fraction, 0.0, 0.99) *
                                             static_cast<double>(values.size()));
  const auto keep = values.size() - drop;
  if (drop > 0)
    std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(keep - 1),
                     values.end());
  double sum = 0.0;
  for (std::size_t i = 0; i < keep; ++i) sum += values[i];
  return std::sqrt(sum / static_cast<double>(keep));
}

Rgb deviation_color(double signed_distance_mm, double scale_mm) {
  const double t = scale_mm > 0.0 ? std::clamp(signed_distance_mm / scale_mm, -1.0, 1.0) : 0.0;
  const auto level = [](double x) { return static_cast<std::uint8_t>(std::lround(255.0 * x)); };
  if (!std::isfinite(t)) return {0, 0, 0};
  if (t < 0.0) return {0, level(1.0 + t), level(-t)};  // green -> blue
  return {level(t), level(1.0 - t), 0};                // green -> red
}

}  // namespace springscan::analysis
