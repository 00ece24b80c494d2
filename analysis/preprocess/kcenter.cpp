#include "analysis/preprocess/kcenter.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <string>

#include "analysis/core/kdtree.hpp"
#include "analysis/core/parallel.hpp"

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

// A KD tree over the points (QuickFPS-style): every node keeps its box and the farthest
// distance to the center set inside its subtree, so a new center descends only into nodes
// whose box is closer than that farthest distance, and the next center is read at the root.
struct Node {
  Vec3 lo, hi;                                              // bounding box
  double far_d2 = std::numeric_limits<double>::infinity();  // max distance^2 in the subtree
  std::uint32_t far_index = 0;                              // its original index (lowest on ties)
  std::size_t begin = 0, end = 0;      // leaf: range in the tree-ordered arrays
  std::int32_t left = -1, right = -1;  // children, -1 for a leaf
};

struct Entry {
  Vec3 p;
  std::uint32_t index;
};

struct PointTree {
  std::vector<Entry> entries;  // points in tree order with their original indices
  std::vector<double> d2;      // current distance^2 to the center set, tree order
  std::vector<Node> nodes;     // nodes[0] is the root
};

// Median splits along the longest box axis until a leaf holds at most `leaf` points.
std::int32_t build(PointTree& t, std::size_t begin, std::size_t end, std::size_t leaf) {
  const auto id = static_cast<std::int32_t>(t.nodes.size());
  t.nodes.emplace_back();
  Node n;
  n.begin = begin;
  n.end = end;
  n.lo = n.hi = t.entries[begin].p;
  for (std::size_t i = begin; i < end; ++i) {
    n.lo = n.lo.cwiseMin(t.entries[i].p);
    n.hi = n.hi.cwiseMax(t.entries[i].p);
  }
  if (end - begin > leaf) {
    int axis = 0;
    (n.hi - n.lo).maxCoeff(&axis);
    const std::size_t mid = begin + (end - begin) / 2;
    std::nth_element(t.entries.begin() + static_cast<std::ptrdiff_t>(begin),
                     t.entries.begin() + static_cast<std::ptrdiff_t>(mid),
                     t.entries.begin() + static_cast<std::ptrdiff_t>(end),
                     [axis](const Entry& a, const Entry& b) {
                       return a.p[axis] < b.p[axis] ||
                              (a.p[axis] == b.p[axis] && a.index < b.index);
                     });
    n.left = build(t, begin, mid, leaf);
    n.right = build(t, mid, end, leaf);
  }
  t.nodes[static_cast<std::size_t>(id)] = n;
  return id;
}

// Lowers distances by the new center c below node `id` and refreshes the subtree maxima.
void update(PointTree& t, std::int32_t id, const Vec3& c) {
  Node& n = t.nodes[static_cast<std::size_t>(id)];
  // Prune: if the box is no closer than the farthest distance inside, no distance can drop.
  if (squared_distance_to_box(c, n.lo, n.hi) >= n.far_d2) return;
  if (n.left < 0) {
    double far_d2 = -1.0;
    std::uint32_t far_index = 0;
    for (std::size_t i = n.begin; i < n.end; ++i) {
      const double d = squared_distance(t.entries[i].p, c);
      if (d < t.d2[i]) t.d2[i] = d;
      if (farther(t.d2[i], t.entries[i].index, far_d2, far_index)) {
        far_d2 = t.d2[i];
        far_index = t.entries[i].index;
      }
    }
    n.far_d2 = far_d2;
    n.far_index = far_index;
    return;
  }
  update(t, n.left, c);
  update(t, n.right, c);
  const Node& a = t.nodes[static_cast<std::size_t>(n.left)];
  const Node& b = t.nodes[static_cast<std::size_t>(n.right)];
  const bool take_b = farther(b.far_d2, b.far_index, a.far_d2, a.far_index);
  n.far_d2 = take_b ? b.far_d2 : a.far_d2;
  n.far_index = take_b ? b.far_index : a.far_index;
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
  PointTree tree;
  tree.entries.reserve(points.size());
  for (std::size_t i = 0; i < points.size(); ++i)
    tree.entries.push_back({points[i], static_cast<std::uint32_t>(i)});
  tree.d2.assign(points.size(), std::numeric_limits<double>::infinity());
  tree.nodes.reserve(2 * points.size() / std::max<std::size_t>(settings.bucket_size, 1) + 2);
  build(tree, 0, points.size(), std::max<std::size_t>(settings.bucket_size, 1));
  std::uint32_t next = settings.start_index;
  double far_d2 = std::numeric_limits<double>::infinity();
  while (result.centers.empty() || !should_stop(result.centers.size(), far_d2, settings)) {
    result.centers.push_back(next);
    update(tree, 0, points[next]);
    far_d2 = tree.nodes[0].far_d2;  // the farthest point from the set, lowest index on ties
    next = tree.nodes[0].far_index;
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
