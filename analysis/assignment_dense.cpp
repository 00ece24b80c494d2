// Dense rectangular assignment by shortest augmenting paths (docs/matching.md "Dense solver").
// The search is the rectangular Jonker-Volgenant variant of D. F. Crouse, "On implementing 2D
// rectangular assignment algorithms", IEEE TAES 52(4), 2016, Algorithm 1; the dual updates keep
// v_j <= 0 and v_j = 0 on unused columns, which is what makes the rectangular certificate hold.
#include <cmath>
#include <limits>
#include <string>

#include "analysis/assignment.hpp"

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
void row_reduction(const DenseCostMatrix& cost, Assignment& a) {
  for (std::size_t i = 0; i < cost.rows; ++i) {
    const double* row = &cost.values[i * cost.cols];
    std::size_t best = 0;
    for (std::size_t j = 1; j < cost.cols; ++j) {
      if (row[j] < row[best]) best = j;
    }
    a.u[i] = row[best];
    if (a.col_to_row[best] < 0) {
      a.col_to_row[best] = static_cast<std::int32_t>(i);
      a.row_to_col[i] = static_cast<std::int32_t>(best);
    }
  }
}

// One Dijkstra-like search from free row `start` over the dense graph (Crouse, Algorithm 1
// lines 9-27), then the dual update and the augmentation. Returns false if no free column is
// reachable (impossible for a finite dense matrix with rows <= cols).
bool augment_from(const DenseCostMatrix& cost, std::int32_t start, Assignment& a,
                  DenseWorkspace& w) {
  const std::size_t n = cost.cols;
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
    const double* row = &cost.values[static_cast<std::size_t>(i) * n];
    const double base = min_val - a.u[static_cast<std::size_t>(i)];
    double lowest = kInf;
    std::size_t lowest_at = 0;
    for (std::size_t k = 0; k < num_remaining; ++k) {
      const auto j = static_cast<std::size_t>(w.remaining[k]);
      const double r = base + row[j] - a.v[j];
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
  Assignment a;
  a.row_to_col.assign(cost.rows, -1);
  a.col_to_row.assign(cost.cols, -1);
  a.u.assign(cost.rows, 0.0);
  a.v.assign(cost.cols, 0.0);
  if (cost.rows == 0) return a;

  row_reduction(cost, a);
  DenseWorkspace w;
  w.pred.assign(cost.cols, -1);
  for (std::size_t i = 0; i < cost.rows; ++i) {
    if (a.row_to_col[i] >= 0) continue;
    if (!augment_from(cost, static_cast<std::int32_t>(i), a, w)) {
      return fail("dense assignment: no augmenting path from row " + std::to_string(i));
    }
    ++a.augmentations;
  }
  for (std::size_t i = 0; i < cost.rows; ++i) {
    a.total_cost += cost.at(i, static_cast<std::size_t>(a.row_to_col[i]));
  }
  return a;
}

}  // namespace springscan::analysis
