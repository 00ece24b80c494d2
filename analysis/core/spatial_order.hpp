#pragma once
// A visiting order of a point set in which neighbours in the order are neighbours in space: the
// order a per-point search loop should run in, whatever order the points came in. A scan read
// from a file, merged from several heads or shuffled costs the nearest-neighbour and
// exact-distance searches twice as much in cache misses as one in scanner lines (issue 37,
// docs/performance.md); run in this order, both cost the same.
//
// Only the order of the searches changes, never the data: a loop visits order[k] and writes
// its result to slot order[k], so its results, and every sum over them taken in index order,
// are those of the loop in index order.

#include <cstdint>
#include <vector>

#include "analysis/core/point_cloud.hpp"

namespace springscan::analysis {

/// Bits per axis of the grid spatial_order sorts by: 2^9 cells along the longest side of the
/// bounding box (0.4 mm cells on a 200 mm part, 4 mm on a 2 m sheet). Finer cells would only
/// cost radix passes: a cell's points already share the search's tree nodes in cache.
inline constexpr int kSpatialOrderBits = 9;

/// A permutation of [0, points.size()): the points by the Morton (Z-order) code of their cell in
/// a grid of cubic cells over their bounding box, kSpatialOrderBits per axis; points of one cell
/// keep their input order. O(n): a stable least-significant-digit radix sort of 9-bit digits, in
/// blocks of a fixed size on up to `threads` threads (0 = all cores); the result does not depend
/// on the thread count. Points must be finite. Thread safety: a pure function.
std::vector<std::uint32_t> spatial_order(const std::vector<Vec3>& points, int threads = 0);

/// spatial_order with the points of one cell by their coordinates (x, then y, then z) instead of
/// their input order: a permutation that depends on the point set alone, not on the order it
/// came in (points with equal coordinates keep their input order; they are the same point).
/// The analysis takes its scan in this order once (analysis/inspection/pipeline.cpp), so that
/// its index-based samples draw the same points, and the same report comes out, whatever order
/// the scan came in. Thread safety: a pure function; the result does not depend on `threads`.
std::vector<std::uint32_t> canonical_order(const std::vector<Vec3>& points, int threads = 0);

/// A permutation and the points in its order.
struct OrderedPoints {
  std::vector<std::uint32_t> order;  ///< points[k] is the input's point order[k]
  std::vector<Vec3> points;
};

/// canonical_order and the points in that order, taken from the copy its sort reads (a gather by
/// the order afterwards would miss the cache on every point a second time).
OrderedPoints canonically_ordered(const std::vector<Vec3>& points, int threads = 0);

/// True when the points are in a spatially coherent order already (a scan in scanner lines, a
/// grid-sorted one): the median distance between consecutive points, over up to 1024 pairs
/// spread evenly, is below 1 % of the diagonal of those pairs' bounding box. A search loop then
/// runs in input order, and spatial_order and the gather it implies would only cost (about 30
/// ms for 1M points). Heuristic and cheap (2,048 reads); it never changes a result.
bool spatially_coherent(const std::vector<Vec3>& points);

/// The order a search loop over `points` should run in: the identity when they are spatially
/// coherent already, spatial_order otherwise.
std::vector<std::uint32_t> search_order(const std::vector<Vec3>& points, int threads = 0);

}  // namespace springscan::analysis
