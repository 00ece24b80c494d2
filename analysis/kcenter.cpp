#include "analysis/kcenter.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <string>

#include "analysis/kdtree.hpp"
#include "analysis/parallel.hpp"

namespace springscan::analysis {
namespace {

// One squared distance formula for both versions, so that they compare identical numbers.
inline double squared_distance(const Vec3& a, const Vec3& b) {
  const double dx = a.x() - b.x(), dy = a.y() - b.y(), dz = a.z() - b.z();
  return dx * dx + dy * dy + dz * dz;
}

// Squared distance from c to an axis-aligned box. Never larger than squared_distance(c, p) for
// a p inside the box, also in floating point (rounding is monotonic), which makes the pruning
// exact rather than approximate.
inline double squared_distance_to_box(const Vec3& c, const Vec3& lo, const Vec3& hi) {
  const double gx = std::max({lo.x() - c.x(), c.x() - hi.x(), 0.0});
  const double gy = std::max({lo.y() - c.y(), c.y() - hi.y(), 0.0});
  const double gz = std::max({lo.z() - c.z(), c.z() - hi.z(), 0.0});
  return gx * gx + gy * gy + gz * gz;
}

// "Farther" with the deterministic tie rule: equal distances go to the lower index.
inline bool farther(double d, std::uint32_t i, double best_d, std::uint32_t best_i) {
  return d > best_d || (d == best_d && i < best_i);
}

// True when the greedy loop should stop before adding a center at squared distance `far_d2`.
bool should_stop(std::size_t selected, double far_d2, const KCenterSettings& s) {
  if (far_d2 <= 0.0) return true;  // every point coincides with a center already
  if (s.center_count > 0) return selected >= s.center_count;
  return far_d2 < s.radius_mm * s.radius_mm;
}

std::optional<Error> check_input(const std::vector<Vec3>& points, const KCenterSettings& s) {
  if (!all_finite(points)) return fail("k-center: input has non-finite (NaN/inf) coordinates");
  if (!points.empty() && s.start_index >= points.size())
    return fail("k-center: start_index " + std::to_string(s.start_index) + " out of range (" +
                std::to_string(points.size()) + " points)");
  if (s.center_count == 0 && !(s.radius_mm > 0.0))
    return fail("k-center: radius_mm must be > 0 when center_count is 0, got " +
                std::to_string(s.radius_mm));
  return std::nullopt;
}

struct Bucket {
  std::size_t begin = 0, end = 0;  // range in the bucket-ordered arrays
  Vec3 lo, hi;                     // bounding box
  double far_d2 = 0.0;             // largest distance to the centers inside this bucket
  std::uint32_t far_index = 0;     // its original index (lowest on ties)
};

// The bucket-ordered copy of the points with their current distance to the center set.
struct BucketedPoints {
  std::vector<Vec3> points;
  std::vector<std::uint32_t> index;
  std::vector<double> d2;
  std::vector<Bucket> buckets;
};

// Median splits along the longest box axis until a bucket holds at most `leaf` points.
BucketedPoints make_buckets(const std::vector<Vec3>& points, std::size_t leaf) {
  BucketedPoints out;
  std::vector<std::uint32_t> order(points.size());
  std::iota(order.begin(), order.end(), 0u);
  std::vector<std::pair<std::size_t, std::size_t>> stack{{0, points.size()}};
  while (!stack.empty()) {
    const auto [begin, end] = stack.back();
    stack.pop_back();
    Bucket b;
    b.begin = begin;
    b.end = end;
    b.lo = b.hi = points[order[begin]];
    for (std::size_t i = begin; i < end; ++i) {
      b.lo = b.lo.cwiseMin(points[order[i]]);
      b.hi = b.hi.cwiseMax(points[order[i]]);
    }
    if (end - begin <= leaf) {
      out.buckets.push_back(b);
      continue;
    }
    int axis = 0;
    (b.hi - b.lo).maxCoeff(&axis);
    const std::size_t mid = begin + (end - begin) / 2;
    std::nth_element(order.begin() + static_cast<std::ptrdiff_t>(begin),
                     order.begin() + static_cast<std::ptrdiff_t>(mid),
                     order.begin() + static_cast<std::ptrdiff_t>(end),
                     [&](std::uint32_t a, std::uint32_t c) {
                       const double pa = points[a][axis], pc = points[c][axis];
                       return pa < pc || (pa == pc && a < c);
                     });
    stack.push_back({mid, end});
    stack.push_back({begin, mid});
  }
  out.index = std::move(order);
  out.points.reserve(points.size());
  for (auto i : out.index) out.points.push_back(points[i]);
  out.d2.assign(points.size(), std::numeric_limits<double>::infinity());
  return out;
}

// Lowers the distances of bucket b's points by the new center c and refreshes its farthest.
void update_bucket(BucketedPoints& bp, Bucket& b, const Vec3& c) {
  double far_d2 = -1.0;
  std::uint32_t far_index = 0;
  for (std::size_t i = b.begin; i < b.end; ++i) {
    const double d = squared_distance(bp.points[i], c);
    if (d < bp.d2[i]) bp.d2[i] = d;
    if (farther(bp.d2[i], bp.index[i], far_d2, far_index)) {
      far_d2 = bp.d2[i];
      far_index = bp.index[i];
    }
  }
  b.far_d2 = far_d2;
  b.far_index = far_index;
}

}  // namespace

Expected<KCenterResult> kcenter_reduce_naive(const std::vector<Vec3>& points,
                                             const KCenterSettings& settings) {
  if (auto error = check_input(points, settings)) return *error;
  KCenterResult result;
  if (points.empty()) return result;
  const std::size_t n = points.size();
  std::vector<double> d2(n, std::numeric_limits<double>::infinity());
  std::uint32_t next = settings.start_index;
  double far_d2 = std::numeric_limits<double>::infinity();
  while (result.centers.empty() || !should_stop(result.centers.size(), far_d2, settings)) {
    result.centers.push_back(next);
    const Vec3 c = points[next];
    far_d2 = -1.0;
    for (std::size_t i = 0; i < n; ++i) {
      const double d = squared_distance(points[i], c);
      if (d < d2[i]) d2[i] = d;
      if (d2[i] > far_d2) {  // strict: the first (lowest) index wins ties
        far_d2 = d2[i];
        next = static_cast<std::uint32_t>(i);
      }
    }
  }
  result.covering_radius_mm = std::sqrt(std::max(far_d2, 0.0));
  return result;
}

Expected<KCenterResult> kcenter_reduce(const std::vector<Vec3>& points,
                                       const KCenterSettings& settings) {
  if (auto error = check_input(points, settings)) return *error;
  KCenterResult result;
  if (points.empty()) return result;
  BucketedPoints bp = make_buckets(points, std::max<std::size_t>(settings.bucket_size, 1));
  std::uint32_t next = settings.start_index;
  double far_d2 = std::numeric_limits<double>::infinity();
  while (result.centers.empty() || !should_stop(result.centers.size(), far_d2, settings)) {
    result.centers.push_back(next);
    const Vec3 c = points[next];
    far_d2 = -1.0;
    for (Bucket& b : bp.buckets) {
      // Prune (QuickFPS idea): if the box is no closer than the bucket's farthest distance,
      // the new center cannot lower any distance inside it.
      if (squared_distance_to_box(c, b.lo, b.hi) < b.far_d2 || result.centers.size() == 1)
        update_bucket(bp, b, c);
      if (farther(b.far_d2, b.far_index, far_d2, next)) {
        far_d2 = b.far_d2;
        next = b.far_index;
      }
    }
  }
  result.covering_radius_mm = std::sqrt(std::max(far_d2, 0.0));
  return result;
}

std::vector<int> neighbor_counts(const std::vector<Vec3>& centers, double radius_mm) {
  std::vector<int> counts(centers.size(), 0);
  if (centers.empty()) return counts;
  const KdTree tree(centers);
  std::vector<Neighbor> found;
  for (std::size_t i = 0; i < centers.size(); ++i) {
    tree.radius(centers[i], radius_mm, found);
    counts[i] = static_cast<int>(found.size()) - 1;  // not counting the center itself
  }
  return counts;
}

std::vector<int> count_histogram(const std::vector<int>& counts) {
  std::vector<int> histogram;
  for (int c : counts) {
    if (c < 0) continue;
    if (static_cast<std::size_t>(c) >= histogram.size())
      histogram.resize(static_cast<std::size_t>(c) + 1, 0);
    ++histogram[static_cast<std::size_t>(c)];
  }
  return histogram;
}

}  // namespace springscan::analysis
