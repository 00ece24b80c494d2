#pragma once
// The one wrapper around nanoflann (STYLE.md §2). A KdTree owns a copy of its points for as
// long as it lives, so it can never outlive the data it indexes.
//
// Thread safety: after construction every query is const and may run concurrently from any
// number of threads. Construction is O(n log n); a nearest query is O(log n) on average.

#include <cstddef>
#include <cstdint>
#include <limits>
#include <memory>
#include <optional>
#include <vector>

#include "analysis/core/point_cloud.hpp"

namespace springscan::analysis {

struct KdTreeSettings {
  int leaf_size = 16;  ///< points per leaf; 10-20 is fastest for 3-D nearest-neighbour queries
};

struct Neighbor {
  std::uint32_t index = 0;        ///< index into the tree's points
  double squared_distance = 0.0;  ///< mm^2
};

class KdTree {
 public:
  /// Builds the tree over `points` (taken by value: pass std::move to avoid a copy).
  explicit KdTree(std::vector<Vec3> points, const KdTreeSettings& settings = {});
  ~KdTree();
  KdTree(KdTree&&) noexcept;
  KdTree& operator=(KdTree&&) noexcept;
  KdTree(const KdTree&) = delete;
  KdTree& operator=(const KdTree&) = delete;

  std::size_t size() const;
  bool empty() const { return size() == 0; }
  const std::vector<Vec3>& points() const;

  /// The nearest point closer than `max_distance` (mm), or nothing (also on an empty tree).
  std::optional<Neighbor> nearest(
      const Vec3& query, double max_distance = std::numeric_limits<double>::infinity()) const;

  /// The k nearest points, closest first; fewer when the tree holds fewer. `out` is overwritten.
  void knn(const Vec3& query, std::size_t k, std::vector<Neighbor>& out) const;

  /// Allocation-free k nearest for hot loops: fills `indices` and `squared_distances` (each with
  /// room for k) closest first and returns how many were found.
  std::size_t knn(const Vec3& query, std::size_t k, std::uint32_t* indices,
                  double* squared_distances) const;

  /// Every point within `radius` (mm, inclusive), closest first. `out` is overwritten.
  void radius(const Vec3& query, double radius, std::vector<Neighbor>& out) const;

  /// The nearest point closer than `max_distance` whose normal (`normals`, one per tree point)
  /// has a positive dot product with `direction`, or nothing; with `max_rank` > 0, only when it
  /// is among the query's max_rank nearest points of any normal. The normal test runs inside the
  /// search, so the search prunes by the nearest such point (a one-sided scan of a solid and the
  /// skin it sees: registration/facing.hpp), in one pass. max_rank is at most 32. With
  /// `min_dot` the dot product must exceed that instead of 0 (unit vectors: the cosine of the
  /// largest angle between the normal and `direction`).
  std::optional<Neighbor> nearest_along(
      const Vec3& query, const std::vector<Vec3>& normals, const Vec3& direction,
      double max_distance = std::numeric_limits<double>::infinity(), std::size_t max_rank = 0,
      double min_dot = 0.0) const;

  /// The k nearest points whose normal agrees with `direction` as in nearest_along, closest
  /// first, into `indices` and `squared_distances` (room for k each); returns how many.
  std::size_t knn_along(const Vec3& query, const std::vector<Vec3>& normals, const Vec3& direction,
                        std::size_t k, std::uint32_t* indices, double* squared_distances) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// Points with a non-negative weight each, searched by the additively weighted squared distance
/// |q - p_j|^2 + w_j. Lifting p_j to (p_j, sqrt(w_j)) in 4-D makes that an ordinary squared
/// distance from (q, 0), so the KD-tree bounds stay exact. The matching certificate uses it
/// (assignment_points.cpp). Owns its data; thread safety as KdTree.
class WeightedKdTree {
 public:
  /// Throws std::invalid_argument if the sizes differ or a weight is negative or not finite.
  WeightedKdTree(const std::vector<Vec3>& points, const std::vector<double>& weights,
                 const KdTreeSettings& settings = {});
  ~WeightedKdTree();
  WeightedKdTree(WeightedKdTree&&) noexcept;
  WeightedKdTree& operator=(WeightedKdTree&&) noexcept;
  WeightedKdTree(const WeightedKdTree&) = delete;
  WeightedKdTree& operator=(const WeightedKdTree&) = delete;

  std::size_t size() const;

  /// The point minimising |query - p_j|^2 + w_j, with that value; nothing on an empty tree.
  std::optional<Neighbor> nearest(const Vec3& query) const;

  /// Every point with |query - p_j|^2 + w_j < bound, unsorted. `out` is overwritten.
  void below(const Vec3& query, double bound, std::vector<Neighbor>& out) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace springscan::analysis
