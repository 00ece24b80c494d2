#pragma once
// k-center reduction (paper §2): choose centers C from P so that every point lies within the
// covering radius w of a center. Greedy farthest-point selection (Gonzalez 1985 / Plesnik 1987)
// adds, at each step, the point farthest from the SET of centers chosen so far; that is the
// 2-approximation of the optimal w. (The paper's text says "farthest to the last-added point";
// see docs/method.md.)
//
// Two variants: `center_count` > 0 selects exactly that many centers (or all points), otherwise
// centers are added while the farthest remaining point is at least `radius_mm` away.
//
// Determinism: the first center is `start_index`; ties in "farthest" go to the lowest index.
// `kcenter_reduce` (spatially pruned, QuickFPS-like KD tree) and `kcenter_reduce_naive` (the
// O(n k) loop) select exactly the same centers in the same order.

#include <cstddef>
#include <cstdint>
#include <vector>

#include "analysis/core/expected.hpp"
#include "analysis/core/point_cloud.hpp"

namespace springscan::analysis {

struct KCenterSettings {
  std::size_t center_count = 0;   ///< > 0: select this many centers (variant "k")
  double radius_mm = 10.0;        ///< otherwise: stop when the farthest point is closer (paper: 10)
  std::uint32_t start_index = 0;  ///< the first center (the paper: "an arbitrary point")
  std::size_t bucket_size = 128;  ///< points per KD-tree leaf of the fast version
};

struct KCenterResult {
  std::vector<std::uint32_t> centers;  ///< indices into the input, in selection order
  double covering_radius_mm = 0.0;     ///< max over points of the distance to the nearest center
};

/// Fast greedy k-center: a KD tree whose nodes keep their box and the farthest distance to the
/// centers inside them; a new center descends only into nodes whose box lies closer than that
/// distance, and the next center is the root's farthest point. O(n log n) to build, then about
/// O(log n + points near the new center) per center on surfaces. Errors: non-finite points,
/// start out of range. Not thread-parallel (one pass per center).
Expected<KCenterResult> kcenter_reduce(const std::vector<Vec3>& points,
                                       const KCenterSettings& settings = {});

/// The reference O(n k) loop (baseline and oracle for the fast version).
Expected<KCenterResult> kcenter_reduce_naive(const std::vector<Vec3>& points,
                                             const KCenterSettings& settings = {});

/// For each of `centers`, how many other centers lie within `radius_mm` (the paper's Figure 4
/// counts this per center). O(k log k) with a KD-tree.
std::vector<int> neighbor_counts(const std::vector<Vec3>& centers, double radius_mm);

/// histogram[c] = how many entries of `counts` equal c.
std::vector<int> count_histogram(const std::vector<int>& counts);

}  // namespace springscan::analysis
