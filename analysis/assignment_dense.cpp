// Dense rectangular assignment by shortest augmenting paths (docs/matching.md "Dense solver").
// The search is the rectangular Jonker-Volgenant variant of D. F. Crouse, "On implementing 2D
// rectangular assignment algorithms", IEEE TAES 52(4), 2016, Algorithm 1; the dual updates keep
// v_j <= 0 and v_j = 0 on unused columns, which is what makes the rectangular certificate hold.
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <string>

#include "analysis/assignment.hpp"
#include "analysis/assignment_init.hpp"

namespace springscan::analysis {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// Scratch space for one augmentation, allocated once per solve.
struct DenseWorkspace {
  std::vector<double> dist;                ///< shortest reduced path cost to each column
  std::vector<std::int32_t> pred;          ///< row preceding each column on its path
  std::vector<std::int32_t> remaining;     ///< columns not yet finalised
  std::vector<std::int32_t> visited_rows;  ///< SR in Crouse's notation
  std::vector<std::int32_t> visited_cols;  ///< SC
};

// Warm start (Jonker-Volgenant "reduction transfer" reduced to rows): u_i = min_j c_ij keeps
// every reduced cost >= 0 with v = 0; a row whose cheapest column is still free takes it.
template <class Costs>
void row_reduction(const Costs& costs, Assignment& a) {
  for (std::size_t i = 0; i < costs.rows(); ++i) {
    const auto row = costs.row(i);
    std::size_t best = 0;
    double best_cost = row(0);
    for (std::size_t j = 1; j < costs.cols(); ++j) {
      const double c = row(j);
      if (c < best_cost) {
        best = j;
        best_cost = c;
      }
    }
    a.u[i] = best_cost;
    if (a.col_to_row[best] < 0) {
      a.col_to_row[best] = static_cast<std::int32_t>(i);
      a.row_to_col[i] = static_cast<std::int32_t>(best);
    }
  }
}

// One Dijkstra-like search from free row `start` over the dense graph (Crouse, Algorithm 1
// lines 9-27), then the dual update and the augmentation. Returns false if no free column is
// reachable (impossible for a finite dense matrix with rows <= cols).
template <class Costs>
bool augment_from(const Costs& costs, std::int32_t start, Assignment& a, DenseWorkspace& w) {
  const std::size_t n = costs.cols();
  w.dist.assign(n, kInf);
  w.remaining.resize(n);
  for (std::size_t k = 0; k < n; ++k) w.remaining[k] = static_cast<std::int32_t>(n - 1 - k);
  std::size_t num_remaining = n;
  w.visited_rows.clear();
  w.visited_cols.clear();

  double min_val = 0.0;
  std::int32_t i = start;
  std::int32_t sink = -1;
  while (sink < 0) {
    w.visited_rows.push_back(i);
    const auto row = costs.row(static_cast<std::size_t>(i));
    const double base = min_val - a.u[static_cast<std::size_t>(i)];
    double lowest = kInf;
    std::size_t lowest_at = 0;
    for (std::size_t k = 0; k < num_remaining; ++k) {
      const auto j = static_cast<std::size_t>(w.remaining[k]);
      const double r = base + row(j) - a.v[j];
      if (r < w.dist[j]) {
        w.pred[j] = i;
        w.dist[j] = r;
      }
      // Ties go to a free column: the path ends sooner.
      if (w.dist[j] < lowest || (w.dist[j] == lowest && a.col_to_row[j] < 0)) {
        lowest = w.dist[j];
        lowest_at = k;
      }
    }
    if (!(lowest < kInf)) return false;
    min_val = lowest;
    const std::int32_t j = w.remaining[lowest_at];
    w.visited_cols.push_back(j);
    w.remaining[lowest_at] = w.remaining[--num_remaining];
    if (a.col_to_row[static_cast<std::size_t>(j)] < 0) {
      sink = j;
    } else {
      i = a.col_to_row[static_cast<std::size_t>(j)];
    }
  }

  // Dual update (Crouse, Algorithm 1 lines 28-33): matched edges stay tight, the rest >= 0.
  a.u[static_cast<std::size_t>(start)] += min_val;
  for (std::size_t k = 1; k < w.visited_rows.size(); ++k) {
    const auto r = static_cast<std::size_t>(w.visited_rows[k]);
    a.u[r] += min_val - w.dist[static_cast<std::size_t>(a.row_to_col[r])];
  }
  for (const std::int32_t c : w.visited_cols) {
    a.v[static_cast<std::size_t>(c)] -= min_val - w.dist[static_cast<std::size_t>(c)];
  }
  // Augment along the predecessor chain back to the start row.
  std::int32_t j = sink;
  while (true) {
    const std::int32_t r = w.pred[static_cast<std::size_t>(j)];
    a.col_to_row[static_cast<std::size_t>(j)] = r;
    std::swap(a.row_to_col[static_cast<std::size_t>(r)], j);
    if (r == start) break;
  }
  return true;
}

// The problem's costs as rows of a matrix in memory.
class MatrixCosts {
 public:
  explicit MatrixCosts(const DenseCostMatrix& m) : m_(m) {}
  std::size_t rows() const { return m_.rows; }
  std::size_t cols() const { return m_.cols; }
  struct Row {
    const double* values;
    double operator()(std::size_t j) const { return values[j]; }
  };
  Row row(std::size_t i) const { return {&m_.values[i * m_.cols]}; }

 private:
  const DenseCostMatrix& m_;
};

// Squared distances computed on the fly from the column points, stored coordinate-wise so the
// inner loop streams three arrays instead of a rows x cols matrix (O(n) memory).
class PointCosts {
 public:
  PointCosts(const std::vector<Vec3>& rows, const std::vector<Vec3>& cols) : rows_(rows) {
    for (int k = 0; k < 3; ++k) coords_[k].resize(cols.size());
    for (std::size_t j = 0; j < cols.size(); ++j) {
      for (int k = 0; k < 3; ++k) coords_[k][j] = cols[j][k];
    }
  }
  std::size_t rows() const { return rows_.size(); }
  std::size_t cols() const { return coords_[0].size(); }
  struct Row {
    double x, y, z;
    const double *xs, *ys, *zs;
    double operator()(std::size_t j) const {
      const double dx = x - xs[j], dy = y - ys[j], dz = z - zs[j];
      return dx * dx + dy * dy + dz * dz;
    }
  };
  Row row(std::size_t i) const {
    const Vec3& p = rows_[i];
    return {p.x(), p.y(), p.z(), coords_[0].data(), coords_[1].data(), coords_[2].data()};
  }

 private:
  const std::vector<Vec3>& rows_;
  std::array<std::vector<double>, 3> coords_;
};

template <class Costs>
Expected<Assignment> solve_with(const Costs& costs) {
  Assignment a;
  a.row_to_col.assign(costs.rows(), -1);
  a.col_to_row.assign(costs.cols(), -1);
  a.u.assign(costs.rows(), 0.0);
  a.v.assign(costs.cols(), 0.0);
  if (costs.rows() == 0) return a;

  // Warm start: greedy row reduction, then Jonker-Volgenant augmenting row reduction.
  row_reduction(costs, a);
  const auto scan_row = [&costs](std::size_t i, auto&& visit) {
    const auto row = costs.row(i);
    for (std::size_t j = 0; j < costs.cols(); ++j) visit(j, row(j));
  };
  if (!detail::augmenting_row_reduction(costs.rows(), scan_row, a)) {
    std::fill(a.row_to_col.begin(), a.row_to_col.end(), -1);
    std::fill(a.col_to_row.begin(), a.col_to_row.end(), -1);
    std::fill(a.v.begin(), a.v.end(), 0.0);
    row_reduction(costs, a);
  }
  DenseWorkspace w;
  w.pred.assign(costs.cols(), -1);
  for (std::size_t i = 0; i < costs.rows(); ++i) {
    if (a.row_to_col[i] >= 0) continue;
    if (!augment_from(costs, static_cast<std::int32_t>(i), a, w)) {
      return fail("dense assignment: no augmenting path from row " + std::to_string(i));
    }
    ++a.augmentations;
  }
  for (std::size_t i = 0; i < costs.rows(); ++i) {
    a.total_cost += costs.row(i)(static_cast<std::size_t>(a.row_to_col[i]));
  }
  return a;
}

}  // namespace

Expected<Assignment> solve_dense(const DenseCostMatrix& cost) {
  if (cost.rows > cost.cols) {
    return fail("dense assignment: " + std::to_string(cost.rows) + " rows > " +
                std::to_string(cost.cols) + " columns (transpose the problem)");
  }
  if (cost.values.size() != cost.rows * cost.cols) {
    return fail("dense assignment: matrix holds " + std::to_string(cost.values.size()) +
                " values, expected rows x cols = " + std::to_string(cost.rows * cost.cols));
  }
  for (std::size_t k = 0; k < cost.values.size(); ++k) {
    if (!std::isfinite(cost.values[k])) {
      return fail("dense assignment: cost at row " + std::to_string(k / cost.cols) +
                  ", column " + std::to_string(k % cost.cols) + " is not finite");
    }
  }
  return solve_with(MatrixCosts(cost));
}

Expected<Assignment> solve_dense_points(const std::vector<Vec3>& rows,
                                        const std::vector<Vec3>& cols) {
  if (rows.size() > cols.size()) {
    return fail("dense assignment: " + std::to_string(rows.size()) + " row points > " +
                std::to_string(cols.size()) + " column points (transpose the problem)");
  }
  for (const auto* set : {&rows, &cols}) {
    for (std::size_t k = 0; k < set->size(); ++k) {
      if (!(*set)[k].allFinite()) {
        return fail(std::string("dense assignment: ") + (set == &rows ? "row" : "column") +
                    " point " + std::to_string(k) + " is not finite");
      }
    }
  }
  return solve_with(PointCosts(rows, cols));
}

}  // namespace springscan::analysis
