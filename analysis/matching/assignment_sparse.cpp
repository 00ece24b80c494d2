// Sparse exact assignment: successive shortest augmenting paths with Dijkstra on reduced costs,
// and the Hopcroft-Karp feasibility check (docs/matching.md "Sparse solver").
#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <queue>
#include <string>
#include <utility>

#include "analysis/matching/assignment.hpp"
#include "analysis/matching/assignment_init.hpp"

namespace springscan::analysis {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

std::size_t to_index(std::int32_t k) { return static_cast<std::size_t>(k); }

std::string validate(const CandidateGraph& g) {
  if (g.rows > g.cols) {
    return std::to_string(g.rows) + " rows > " + std::to_string(g.cols) + " columns";
  }
  if (g.row_offsets.size() != g.rows + 1 || g.row_offsets.front() != 0 ||
      g.row_offsets.back() != g.col_index.size() || g.costs.size() != g.col_index.size()) {
    return "row_offsets/col_index/costs sizes disagree";
  }
  for (std::size_t i = 0; i < g.rows; ++i) {
    if (g.row_offsets[i] > g.row_offsets[i + 1]) {
      return "row_offsets decrease at row " + std::to_string(i);
    }
  }
  for (std::size_t e = 0; e < g.col_index.size(); ++e) {
    if (g.col_index[e] < 0 || to_index(g.col_index[e]) >= g.cols) {
      return "edge " + std::to_string(e) + " has column " + std::to_string(g.col_index[e]);
    }
    if (!std::isfinite(g.costs[e])) return "edge " + std::to_string(e) + " cost is not finite";
  }
  return {};
}

// Per-search state; `touched` lists the columns whose entries must be reset afterwards, so a
// search costs O(explored) rather than O(n).
struct SparseWorkspace {
  std::vector<double> dist;
  std::vector<std::int32_t> pred;
  std::vector<std::uint8_t> done;  ///< column finalised (SC)
  std::vector<std::int32_t> touched;
  std::vector<std::int32_t> visited_rows;
  std::vector<std::int32_t> visited_cols;
  using Item = std::pair<double, std::int32_t>;
  std::priority_queue<Item, std::vector<Item>, std::greater<Item>> heap;
};

// Warm start as in the dense solver: u_i = cheapest edge of row i (its nearest candidate).
void row_reduction(const CandidateGraph& g, Assignment& a) {
  for (std::size_t i = 0; i < g.rows; ++i) {
    std::size_t best = g.row_offsets[i];
    if (best == g.row_offsets[i + 1]) continue;
    for (std::size_t e = best + 1; e < g.row_offsets[i + 1]; ++e) {
      if (g.costs[e] < g.costs[best]) best = e;
    }
    a.u[i] = g.costs[best];
    const auto j = to_index(g.col_index[best]);
    if (a.col_to_row[j] < 0) {
      a.col_to_row[j] = static_cast<std::int32_t>(i);
      a.row_to_col[i] = static_cast<std::int32_t>(j);
    }
  }
}

// Dijkstra from free row `start` over reduced costs; the same dual update and augmentation as
// the dense solver, restricted to the explored part of the graph. One function on purpose (a
// little over 60 lines): the search, the dual update and the augmentation share the workspace
// invariants, which read best in one place.
bool augment_from(const CandidateGraph& g, std::int32_t start, Assignment& a, SparseWorkspace& w) {
  w.visited_rows.clear();
  w.visited_cols.clear();
  w.touched.clear();
  while (!w.heap.empty()) w.heap.pop();
  double min_val = 0.0;
  std::int32_t i = start;
  std::int32_t sink = -1;
  while (sink < 0) {
    w.visited_rows.push_back(i);
    const auto r = to_index(i);
    const double base = min_val - a.u[r];
    for (std::size_t e = g.row_offsets[r]; e < g.row_offsets[r + 1]; ++e) {
      const auto j = to_index(g.col_index[e]);
      if (w.done[j]) continue;
      const double d = base + g.costs[e] - a.v[j];
      if (d < w.dist[j]) {
        if (w.dist[j] == kInf) w.touched.push_back(static_cast<std::int32_t>(j));
        w.dist[j] = d;
        w.pred[j] = i;
        w.heap.emplace(d, static_cast<std::int32_t>(j));
      }
    }
    std::int32_t next = -1;
    while (!w.heap.empty()) {
      const auto [d, j] = w.heap.top();
      w.heap.pop();
      if (!w.done[to_index(j)] && d == w.dist[to_index(j)]) {
        next = j;
        break;
      }
    }
    if (next < 0) break;  // every reachable column is matched: no augmenting path
    min_val = w.dist[to_index(next)];
    w.done[to_index(next)] = 1;
    w.visited_cols.push_back(next);
    if (a.col_to_row[to_index(next)] < 0) {
      sink = next;
    } else {
      i = a.col_to_row[to_index(next)];
    }
  }
  if (sink >= 0) {
    a.u[to_index(start)] += min_val;
    for (std::size_t k = 1; k < w.visited_rows.size(); ++k) {
      const auto r = to_index(w.visited_rows[k]);
      a.u[r] += min_val - w.dist[to_index(a.row_to_col[r])];
    }
    for (const std::int32_t c : w.visited_cols) {
      a.v[to_index(c)] -= min_val - w.dist[to_index(c)];
    }
    std::int32_t j = sink;
    while (true) {
      const std::int32_t r = w.pred[to_index(j)];
      a.col_to_row[to_index(j)] = r;
      std::swap(a.row_to_col[to_index(r)], j);
      if (r == start) break;
    }
  }
  for (const std::int32_t c : w.touched) {
    w.dist[to_index(c)] = kInf;
    w.done[to_index(c)] = 0;
  }
  return sink >= 0;
}

void reset(Assignment& a) {
  std::fill(a.row_to_col.begin(), a.row_to_col.end(), -1);
  std::fill(a.col_to_row.begin(), a.col_to_row.end(), -1);
  std::fill(a.v.begin(), a.v.end(), 0.0);
  std::fill(a.u.begin(), a.u.end(), 0.0);
}

// Warm start (docs/matching.md "Warm start"): for square graphs an epsilon-scaling auction
// sets near-optimal column potentials and its tight rows are kept; otherwise greedy row
// reduction. Then Jonker-Volgenant augmenting row reduction for the rows still free. Every
// step keeps v <= 0, v = 0 on unused columns and assigned rows tight.
void warm_start(const CandidateGraph& g, Assignment& a) {
  const auto scan_row = [&g](std::size_t i, auto&& visit) {
    for (std::size_t e = g.row_offsets[i]; e < g.row_offsets[i + 1]; ++e) {
      visit(static_cast<std::size_t>(g.col_index[e]), g.costs[e]);
    }
  };
  bool auctioned = false;
  if (g.rows == g.cols && g.rows > 1 && g.edge_count() > 0) {
    const auto [lo, hi] = std::minmax_element(g.costs.begin(), g.costs.end());
    const double range = *hi - *lo;
    if (range > 0.0) {
      auctioned = detail::epsilon_scaling_auction(g.rows, scan_row, range / 8.0, range * 1e-7, 8.0,
                                                  range, 64 * g.rows + 1024, a);
      if (auctioned) {
        detail::tighten_rows(g.rows, scan_row, a);
      } else {
        reset(a);
      }
    }
  }
  if (!auctioned) row_reduction(g, a);
  if (!detail::augmenting_row_reduction(g.rows, scan_row, a)) {
    reset(a);
    row_reduction(g, a);
  }
}

// Near-square rectangular graphs: n - m dummy rows of cost 0 to every column make the problem
// square, so the auction warm start applies. In the square optimum every dummy column has the
// largest v (a dummy's u_d + v_j <= 0 is tight on its own column), so shifting v by that
// maximum V (and u by +V) gives v <= 0 and v = 0 on the columns the real rows leave unused:
// the rectangular certificate (docs/matching.md).
CandidateGraph with_dummy_rows(const CandidateGraph& g) {
  CandidateGraph square = g;
  for (std::size_t d = g.rows; d < g.cols; ++d) {
    for (std::size_t j = 0; j < g.cols; ++j) {
      square.col_index.push_back(static_cast<std::int32_t>(j));
      square.costs.push_back(0.0);
    }
    square.row_offsets.push_back(square.col_index.size());
  }
  square.rows = g.cols;
  return square;
}

Assignment drop_dummy_rows(const CandidateGraph& g, Assignment square) {
  double shift = -kInf;
  for (std::size_t j = 0; j < g.cols; ++j) {
    if (to_index(square.col_to_row[j]) >= g.rows) shift = std::max(shift, square.v[j]);
  }
  Assignment a;
  a.row_to_col.assign(square.row_to_col.begin(),
                      square.row_to_col.begin() + static_cast<std::ptrdiff_t>(g.rows));
  a.col_to_row = std::move(square.col_to_row);
  for (auto& r : a.col_to_row) {
    if (r >= 0 && to_index(r) >= g.rows) r = -1;
  }
  a.u.assign(square.u.begin(), square.u.begin() + static_cast<std::ptrdiff_t>(g.rows));
  a.v = std::move(square.v);
  for (double& x : a.u) x += shift;
  for (double& x : a.v) x -= shift;
  a.total_cost = square.total_cost;  // dummy edges cost 0
  a.augmentations = square.augmentations;
  return a;
}

}  // namespace

Expected<Assignment> solve_sparse(const CandidateGraph& graph) {
  if (const std::string problem = validate(graph); !problem.empty()) {
    return fail("sparse assignment: " + problem);
  }
  // Feasibility first (Hopcroft-Karp): the auction would otherwise bid until its budget ends.
  if (const std::size_t matched = maximum_matching_size(graph); matched < graph.rows) {
    return fail(
        "sparse assignment: no row-saturating matching in the candidate graph (a maximum "
        "matching places " +
        std::to_string(matched) + " of " + std::to_string(graph.rows) + " rows)");
  }
  // Dummy rows cost (n - m) n edges: only when that does not outgrow the graph itself.
  if (graph.rows > 0 && graph.rows < graph.cols &&
      (graph.cols - graph.rows) * graph.cols <= graph.edge_count()) {
    auto square = solve_sparse(with_dummy_rows(graph));
    if (!square.ok()) return square;
    return drop_dummy_rows(graph, std::move(square).value());
  }
  Assignment a;
  a.row_to_col.assign(graph.rows, -1);
  a.col_to_row.assign(graph.cols, -1);
  a.u.assign(graph.rows, 0.0);
  a.v.assign(graph.cols, 0.0);
  warm_start(graph, a);

  SparseWorkspace w;
  w.dist.assign(graph.cols, kInf);
  w.pred.assign(graph.cols, -1);
  w.done.assign(graph.cols, 0);
  for (std::size_t i = 0; i < graph.rows; ++i) {
    if (a.row_to_col[i] >= 0) continue;
    if (!augment_from(graph, static_cast<std::int32_t>(i), a, w)) {
      return fail("sparse assignment: no row-saturating matching in the candidate graph (row " +
                  std::to_string(i) + " cannot be placed)");
    }
    ++a.augmentations;
  }
  for (std::size_t i = 0; i < graph.rows; ++i) {
    // The cheapest of possibly parallel edges is the one the search used.
    double matched = kInf;
    for (std::size_t e = graph.row_offsets[i]; e < graph.row_offsets[i + 1]; ++e) {
      if (graph.col_index[e] == a.row_to_col[i]) matched = std::min(matched, graph.costs[e]);
    }
    a.total_cost += matched;
  }
  return a;
}

}  // namespace springscan::analysis
