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

#include "analysis/point_cloud.hpp"

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

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace springscan::analysis
