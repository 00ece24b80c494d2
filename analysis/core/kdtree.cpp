#include "analysis/core/kdtree.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <nanoflann.hpp>
#include <stdexcept>
#include <string>
#include <utility>

namespace springscan::analysis {
namespace {

// nanoflann's dataset contract: count, coordinate access, and no precomputed bounding box.
struct PointsAdaptor {
  const std::vector<Vec3>* points;
  std::size_t kdtree_get_point_count() const { return points->size(); }
  double kdtree_get_pt(std::size_t i, std::size_t dim) const { return (*points)[i][dim]; }
  template <class Box>
  bool kdtree_get_bbox(Box&) const {
    return false;
  }
};

using Index = nanoflann::KDTreeSingleIndexAdaptor<
    nanoflann::L2_Simple_Adaptor<double, PointsAdaptor, double, std::uint32_t>, PointsAdaptor, 3,
    std::uint32_t>;

// A result set that keeps only the single closest point below an initial bound, so that
// nearest-within-distance prunes the search from the start.
class NearestWithin {
 public:
  explicit NearestWithin(double max_squared_distance) : best_(max_squared_distance) {}
  bool addPoint(double squared_distance, std::uint32_t index) {
    if (squared_distance < best_) {
      best_ = squared_distance;
      index_ = index;
      found_ = true;
    }
    return true;
  }
  double worstDist() const { return best_; }
  bool full() const { return true; }
  bool found() const { return found_; }
  Neighbor neighbor() const { return {index_, best_}; }

 private:
  double best_;
  std::uint32_t index_ = 0;
  bool found_ = false;
};

// NearestWithin, counting only points whose normal has a dot product with a direction above a
// floor (0: a positive one).
// With a rank limit it also keeps the `rank` smallest distances of the other points it is offered
// below the best so far: the search offers every point closer than the final best, so the best
// is among the rank nearest unless all rank of those lie below it. One pass, pruned by the best.
class NearestAlong {
 public:
  static constexpr std::size_t kMaxRank = 32;
  NearestAlong(double max_squared_distance, const std::vector<Vec3>& normals, const Vec3& direction,
               std::size_t rank, double min_dot)
      : best_(max_squared_distance),
        normals_(normals),
        direction_(direction),
        min_dot_(min_dot),
        rank_(std::min(rank, kMaxRank)) {}
  bool addPoint(double squared_distance, std::uint32_t index) {
    if (!(squared_distance < best_)) return true;
    if (normals_[index].dot(direction_) > min_dot_) {
      best_ = squared_distance;
      index_ = index;
      found_ = true;
    } else if (rank_ > 0) {
      keep_closer(squared_distance);
    }
    return true;
  }
  double worstDist() const { return best_; }
  bool full() const { return true; }
  // Found, and (with a rank limit) fewer than `rank` other points closer.
  bool found() const {
    return found_ && !(rank_ > 0 && closer_ == rank_ && other_[rank_ - 1] < best_);
  }
  Neighbor neighbor() const { return {index_, best_}; }

 private:
  void keep_closer(double squared_distance) {
    if (closer_ == rank_ && !(squared_distance < other_[rank_ - 1])) return;
    std::size_t i = closer_ < rank_ ? closer_++ : rank_ - 1;
    for (; i > 0 && other_[i - 1] > squared_distance; --i) other_[i] = other_[i - 1];
    other_[i] = squared_distance;
  }
  double best_;
  const std::vector<Vec3>& normals_;
  const Vec3& direction_;
  double min_dot_;
  std::size_t rank_, closer_ = 0;
  std::array<double, kMaxRank> other_{};
  std::uint32_t index_ = 0;
  bool found_ = false;
};

// The k nearest points whose normal agrees with a direction, closest first (insertion into a
// short sorted list: k is a handful).
class KnnAlong {
 public:
  KnnAlong(std::size_t k, std::uint32_t* indices, double* squared_distances,
           const std::vector<Vec3>& normals, const Vec3& direction)
      : k_(k),
        indices_(indices),
        d2_(squared_distances),
        normals_(normals),
        direction_(direction) {}
  bool addPoint(double squared_distance, std::uint32_t index) {
    if (squared_distance >= worstDist() || !(normals_[index].dot(direction_) > 0.0)) return true;
    std::size_t i = count_ < k_ ? count_++ : k_ - 1;
    for (; i > 0 && d2_[i - 1] > squared_distance; --i) {
      d2_[i] = d2_[i - 1];
      indices_[i] = indices_[i - 1];
    }
    d2_[i] = squared_distance;
    indices_[i] = index;
    return true;
  }
  double worstDist() const {
    return count_ < k_ ? std::numeric_limits<double>::infinity() : d2_[k_ - 1];
  }
  bool full() const { return count_ == k_; }
  std::size_t size() const { return count_; }

 private:
  std::size_t k_, count_ = 0;
  std::uint32_t* indices_;
  double* d2_;
  const std::vector<Vec3>& normals_;
  const Vec3& direction_;
};

// nanoflann's tree copied for the nearest search, the hot query of every stage (ICP pairs,
// boundary contacts, flange assignment: a third of the analysis's CPU, docs/performance.md):
// nodes in one array in depth-first order (a node's first child follows it) and each leaf's
// points in one contiguous run, where nanoflann reads them through its index array. The search
// is nanoflann's searchLevel step for step (the same children in the same order, the same
// pruning test, the same sums in the same order: no FMA contraction at -std=c++20), so it
// finds the same point, equal distances included (the first one visited).
class FlatTree {
 public:
  FlatTree(const Index& index, const std::vector<Vec3>& points) {
    if (index.root_node == nullptr) return;
    for (int i = 0; i < 3; ++i) {
      low_[i] = index.root_bbox[i].low;
      high_[i] = index.root_bbox[i].high;
    }
    leaf_points_.reserve(points.size());
    leaf_index_.reserve(points.size());
    copy(index, index.root_node, points);
  }

  // nanoflann's findNeighbors with eps 0: `result` (a nanoflann result set) is offered the
  // same points in the same order.
  template <typename ResultSet>
  void find(ResultSet& result, const Vec3& query) const {
    if (nodes_.empty()) return;
    std::array<double, 3> dists{0.0, 0.0, 0.0};
    double distsq = 0.0;
    for (int i = 0; i < 3; ++i) {  // nanoflann's computeInitialDistances
      if (query[i] < low_[i]) {
        dists[i] = (query[i] - low_[i]) * (query[i] - low_[i]);
        distsq += dists[i];
      }
      if (query[i] > high_[i]) {
        dists[i] = (query[i] - high_[i]) * (query[i] - high_[i]);
        distsq += dists[i];
      }
    }
    search(result, 0, query.data(), distsq, dists);
  }

 private:
  struct Node {
    double low = 0.0, high = 0.0;  // inner: the split's divlow and divhigh
    std::uint32_t begin = 0;       // leaf: its points' run; inner: unused (child1 is next)
    std::uint32_t end = 0;         // leaf: end of the run; inner: the second child
    int axis = -1;                 // inner: the split's axis; leaf: -1
  };
  template <typename NodePtr>
  std::uint32_t copy(const Index& index, NodePtr node, const std::vector<Vec3>& points) {
    const auto at = static_cast<std::uint32_t>(nodes_.size());
    nodes_.emplace_back();
    if (node->child1 == nullptr && node->child2 == nullptr) {
      nodes_[at].begin = static_cast<std::uint32_t>(leaf_points_.size());
      for (auto i = node->node_type.lr.left; i < node->node_type.lr.right; ++i) {
        leaf_points_.push_back(points[index.vAcc[i]]);
        leaf_index_.push_back(index.vAcc[i]);
      }
      nodes_[at].end = static_cast<std::uint32_t>(leaf_points_.size());
      return at;
    }
    nodes_[at].axis = static_cast<int>(node->node_type.sub.divfeat);
    nodes_[at].low = node->node_type.sub.divlow;
    nodes_[at].high = node->node_type.sub.divhigh;
    copy(index, node->child1, points);
    const std::uint32_t second = copy(index, node->child2, points);
    nodes_[at].end = second;
    return at;
  }

  // nanoflann's searchLevel with eps 0 (mindistsq * 1.0f is exact); false when the result set
  // wants no more points.
  template <typename ResultSet>
  bool search(ResultSet& result, std::uint32_t at, const double* q, double mindistsq,
              std::array<double, 3>& dists) const {
    const Node& node = nodes_[at];
    if (node.axis < 0) {
      const double worst = result.worstDist();
      for (std::uint32_t k = node.begin; k < node.end; ++k) {
        const double* p = leaf_points_[k].data();
        const double dx = q[0] - p[0], dy = q[1] - p[1], dz = q[2] - p[2];
        double d = dx * dx;  // L2_Simple_Adaptor::evalMetric's sum, in its order
        d += dy * dy;
        d += dz * dz;
        if (d < worst && !result.addPoint(d, leaf_index_[k])) return false;
      }
      return true;
    }
    const int axis = node.axis;
    const double val = q[axis];
    const double diff1 = val - node.low, diff2 = val - node.high;
    std::uint32_t near_child, far_child;
    double cut_dist;
    if ((diff1 + diff2) < 0) {
      near_child = at + 1;
      far_child = node.end;
      cut_dist = (val - node.high) * (val - node.high);
    } else {
      near_child = node.end;
      far_child = at + 1;
      cut_dist = (val - node.low) * (val - node.low);
    }
    if (!search(result, near_child, q, mindistsq, dists)) return false;
    const double dst = dists[axis];
    mindistsq = mindistsq + cut_dist - dst;
    dists[axis] = cut_dist;
    if (mindistsq <= result.worstDist() && !search(result, far_child, q, mindistsq, dists))
      return false;
    dists[axis] = dst;
    return true;
  }

  std::vector<Node> nodes_;
  std::vector<Vec3> leaf_points_;
  std::vector<std::uint32_t> leaf_index_;
  double low_[3] = {0.0, 0.0, 0.0}, high_[3] = {0.0, 0.0, 0.0};
};

}  // namespace

struct KdTree::Impl {
  Impl(std::vector<Vec3> pts, const KdTreeSettings& settings)
      : points(std::move(pts)),
        adaptor{&points},
        index(3, adaptor,
              nanoflann::KDTreeSingleIndexAdaptorParams(
                  static_cast<std::size_t>(settings.leaf_size > 0 ? settings.leaf_size : 16))),
        flat(index, points) {}
  std::vector<Vec3> points;
  PointsAdaptor adaptor;
  Index index;
  FlatTree flat;
};

KdTree::KdTree(std::vector<Vec3> points, const KdTreeSettings& settings)
    : impl_(std::make_unique<Impl>(std::move(points), settings)) {}
KdTree::~KdTree() = default;
KdTree::KdTree(KdTree&&) noexcept = default;
KdTree& KdTree::operator=(KdTree&&) noexcept = default;

std::size_t KdTree::size() const { return impl_->points.size(); }
const std::vector<Vec3>& KdTree::points() const { return impl_->points; }

std::optional<Neighbor> KdTree::nearest(const Vec3& query, double max_distance) const {
  if (empty() || !(max_distance > 0.0)) return std::nullopt;
  const double bound = max_distance == std::numeric_limits<double>::infinity()
                           ? std::numeric_limits<double>::infinity()
                           : max_distance * max_distance;
  NearestWithin result(bound);
  impl_->flat.find(result, query);
  if (!result.found()) return std::nullopt;
  return result.neighbor();
}

std::size_t KdTree::knn(const Vec3& query, std::size_t k, std::uint32_t* indices,
                        double* squared_distances) const {
  if (empty() || k == 0) return 0;
  nanoflann::KNNResultSet<double, std::uint32_t, std::size_t> result(k);
  result.init(indices, squared_distances);
  impl_->flat.find(result, query);
  return result.size();
}

void KdTree::knn(const Vec3& query, std::size_t k, std::vector<Neighbor>& out) const {
  out.clear();
  if (empty() || k == 0) return;
  std::vector<std::uint32_t> indices(k);
  std::vector<double> distances(k);
  const std::size_t found = knn(query, k, indices.data(), distances.data());
  out.reserve(found);
  for (std::size_t i = 0; i < found; ++i) out.push_back({indices[i], distances[i]});
}

void KdTree::radius(const Vec3& query, double radius, std::vector<Neighbor>& out) const {
  out.clear();
  if (empty() || !(radius >= 0.0)) return;
  std::vector<std::pair<std::uint32_t, double>> found;
  // nanoflann's radius search is strict (d < r); widen by one ulp so that r is inclusive.
  const double r2 = std::nextafter(radius * radius, std::numeric_limits<double>::infinity());
  // nanoflann's radiusSearch, sorted: the same result set and the same sort of what it found.
  nanoflann::RadiusResultSet<double, std::uint32_t> result(r2, found);
  impl_->flat.find(result, query);
  std::sort(found.begin(), found.end(), nanoflann::IndexDist_Sorter());
  out.reserve(found.size());
  for (const auto& [index, d2] : found) out.push_back({index, d2});
}

std::optional<Neighbor> KdTree::nearest_along(const Vec3& query, const std::vector<Vec3>& normals,
                                              const Vec3& direction, double max_distance,
                                              std::size_t max_rank, double min_dot) const {
  if (empty() || !(max_distance > 0.0) || normals.size() != size()) return std::nullopt;
  const double bound = max_distance == std::numeric_limits<double>::infinity()
                           ? std::numeric_limits<double>::infinity()
                           : max_distance * max_distance;
  NearestAlong result(bound, normals, direction, max_rank, min_dot);
  impl_->flat.find(result, query);
  if (!result.found()) return std::nullopt;
  return result.neighbor();
}

std::size_t KdTree::knn_along(const Vec3& query, const std::vector<Vec3>& normals,
                              const Vec3& direction, std::size_t k, std::uint32_t* indices,
                              double* squared_distances) const {
  if (empty() || k == 0 || normals.size() != size()) return 0;
  KnnAlong result(k, indices, squared_distances, normals, direction);
  impl_->flat.find(result, query);
  return result.size();
}

// ---- WeightedKdTree: (p, sqrt(w)) in 4-D --------------------------------------------------

namespace {

struct Lifted {
  std::vector<std::array<double, 4>> points;
  std::size_t kdtree_get_point_count() const { return points.size(); }
  double kdtree_get_pt(std::size_t i, std::size_t dim) const { return points[i][dim]; }
  template <class Box>
  bool kdtree_get_bbox(Box&) const {
    return false;
  }
};

using LiftedIndex = nanoflann::KDTreeSingleIndexAdaptor<
    nanoflann::L2_Simple_Adaptor<double, Lifted, double, std::uint32_t>, Lifted, 4, std::uint32_t>;

Lifted lift(const std::vector<Vec3>& points, const std::vector<double>& weights) {
  if (points.size() != weights.size()) {
    throw std::invalid_argument("WeightedKdTree: " + std::to_string(points.size()) +
                                " points but " + std::to_string(weights.size()) + " weights");
  }
  Lifted lifted;
  lifted.points.reserve(points.size());
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (!(weights[i] >= 0.0) || !std::isfinite(weights[i])) {
      throw std::invalid_argument("WeightedKdTree: weight " + std::to_string(i) + " = " +
                                  std::to_string(weights[i]) + " (must be finite and >= 0)");
    }
    lifted.points.push_back({points[i].x(), points[i].y(), points[i].z(), std::sqrt(weights[i])});
  }
  return lifted;
}

}  // namespace

struct WeightedKdTree::Impl {
  Impl(const std::vector<Vec3>& p, const std::vector<double>& w, const KdTreeSettings& settings)
      : points(p),
        weights(w),
        lifted(lift(p, w)),
        index(4, lifted,
              nanoflann::KDTreeSingleIndexAdaptorParams(
                  static_cast<std::size_t>(settings.leaf_size > 0 ? settings.leaf_size : 16))) {}
  // The exact weighted distance (the lifted one squares a rounded square root).
  double value(const Vec3& q, std::uint32_t j) const {
    return (q - points[j]).squaredNorm() + weights[j];
  }
  std::vector<Vec3> points;
  std::vector<double> weights;
  Lifted lifted;
  LiftedIndex index;
};

WeightedKdTree::WeightedKdTree(const std::vector<Vec3>& points, const std::vector<double>& weights,
                               const KdTreeSettings& settings)
    : impl_(std::make_unique<Impl>(points, weights, settings)) {}
WeightedKdTree::~WeightedKdTree() = default;
WeightedKdTree::WeightedKdTree(WeightedKdTree&&) noexcept = default;
WeightedKdTree& WeightedKdTree::operator=(WeightedKdTree&&) noexcept = default;

std::size_t WeightedKdTree::size() const { return impl_->points.size(); }

std::optional<Neighbor> WeightedKdTree::nearest(const Vec3& query) const {
  if (size() == 0) return std::nullopt;
  const double q[4] = {query.x(), query.y(), query.z(), 0.0};
  std::uint32_t index = 0;
  double d2 = 0.0;
  nanoflann::KNNResultSet<double, std::uint32_t, std::size_t> result(1);
  result.init(&index, &d2);
  impl_->index.findNeighbors(result, q, nanoflann::SearchParams());
  return Neighbor{index, impl_->value(query, index)};
}

void WeightedKdTree::below(const Vec3& query, double bound, std::vector<Neighbor>& out) const {
  out.clear();
  if (size() == 0 || !(bound > 0.0)) return;
  const double q[4] = {query.x(), query.y(), query.z(), 0.0};
  std::vector<std::pair<std::uint32_t, double>> found;
  // Widened by a relative 1e-12 so rounding in the lifted distance cannot hide a point; the
  // exact value then decides.
  impl_->index.radiusSearch(q, bound * (1.0 + 1e-12), found,
                            nanoflann::SearchParams(32, 0.0f, false));
  for (const auto& [index, lifted_d2] : found) {
    const double exact = impl_->value(query, index);
    if (exact < bound) out.push_back({index, exact});
  }
}

}  // namespace springscan::analysis
