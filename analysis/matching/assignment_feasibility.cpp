// Hopcroft-Karp maximum cardinality matching (J. E. Hopcroft, R. M. Karp, SIAM J. Comput.
// 2(4), 1973): decides whether a candidate graph admits a row-saturating matching before the
// weighted solver runs (docs/matching.md "Feasibility and widening").
#include <limits>
#include <vector>

#include "analysis/matching/assignment.hpp"

namespace springscan::analysis {
namespace {

constexpr std::size_t kUnreached = std::numeric_limits<std::size_t>::max();

class HopcroftKarp {
 public:
  explicit HopcroftKarp(const CandidateGraph& g)
      : g_(g),
        row_match_(g.rows, -1),
        col_match_(g.cols, -1),
        layer_(g.rows, kUnreached),
        next_edge_(g.rows, 0) {}

  /// Starts from `start` (a column per row or -1); entries that are not an edge of their row,
  /// or reuse a column, are dropped. Returns the size of what was kept.
  std::size_t seed(const std::vector<std::int32_t>& start) {
    std::size_t size = 0;
    for (std::size_t i = 0; i < g_.rows && i < start.size(); ++i) {
      const std::int32_t j = start[i];
      if (j < 0 || static_cast<std::size_t>(j) >= g_.cols ||
          col_match_[static_cast<std::size_t>(j)] >= 0) {
        continue;
      }
      for (std::size_t e = g_.row_offsets[i]; e < g_.row_offsets[i + 1]; ++e) {
        if (g_.col_index[e] != j) continue;
        row_match_[i] = j;
        col_match_[static_cast<std::size_t>(j)] = static_cast<std::int32_t>(i);
        ++size;
        break;
      }
    }
    return size;
  }

  /// Completes the matching to a maximum one; returns its size.
  std::size_t run(std::size_t size) {
    size += greedy();
    while (build_layers()) {
      for (std::size_t i = 0; i < g_.rows; ++i) next_edge_[i] = g_.row_offsets[i];
      for (std::size_t i = 0; i < g_.rows; ++i) {
        if (row_match_[i] < 0 && augment(i)) ++size;
      }
    }
    return size;
  }

  const std::vector<std::int32_t>& row_match() const { return row_match_; }

 private:
  // Each free row takes its first free candidate (its nearest, on a k-nearest graph): most
  // rows are matched before the first phase, so few phases remain.
  std::size_t greedy() {
    std::size_t size = 0;
    for (std::size_t i = 0; i < g_.rows; ++i) {
      if (row_match_[i] >= 0) continue;
      for (std::size_t e = g_.row_offsets[i]; e < g_.row_offsets[i + 1]; ++e) {
        const auto j = static_cast<std::size_t>(g_.col_index[e]);
        if (col_match_[j] >= 0) continue;
        col_match_[j] = static_cast<std::int32_t>(i);
        row_match_[i] = static_cast<std::int32_t>(j);
        ++size;
        break;
      }
    }
    return size;
  }

  // BFS from all free rows through alternating paths; true if some free column is reachable.
  bool build_layers() {
    std::vector<std::size_t> queue;
    queue.reserve(g_.rows);
    for (std::size_t i = 0; i < g_.rows; ++i) {
      layer_[i] = row_match_[i] < 0 ? 0 : kUnreached;
      if (row_match_[i] < 0) queue.push_back(i);
    }
    bool found = false;
    for (std::size_t head = 0; head < queue.size(); ++head) {
      const std::size_t i = queue[head];
      for (std::size_t e = g_.row_offsets[i]; e < g_.row_offsets[i + 1]; ++e) {
        const std::int32_t r = col_match_[static_cast<std::size_t>(g_.col_index[e])];
        if (r < 0) {
          found = true;
        } else if (layer_[static_cast<std::size_t>(r)] == kUnreached) {
          layer_[static_cast<std::size_t>(r)] = layer_[i] + 1;
          queue.push_back(static_cast<std::size_t>(r));
        }
      }
    }
    return found;
  }

  // DFS along the layers with an explicit stack, so long alternating paths cannot overflow
  // the call stack. Each row's edge cursor only advances (blocking flow).
  bool augment(std::size_t root) {
    std::vector<std::size_t>& stack = stack_;
    stack.assign(1, root);
    while (!stack.empty()) {
      const std::size_t i = stack.back();
      if (next_edge_[i] == g_.row_offsets[i + 1]) {
        layer_[i] = kUnreached;  // dead end for this phase
        stack.pop_back();
        continue;
      }
      const auto j = static_cast<std::size_t>(g_.col_index[next_edge_[i]]);
      const std::int32_t r = col_match_[j];
      if (r < 0) {
        // Flip the path: each stacked row takes the column its cursor points at.
        for (const std::size_t row : stack) {
          const auto col = g_.col_index[next_edge_[row]];
          row_match_[row] = col;
          col_match_[static_cast<std::size_t>(col)] = static_cast<std::int32_t>(row);
          layer_[row] = kUnreached;  // paths of one phase are vertex-disjoint
        }
        return true;
      }
      if (layer_[static_cast<std::size_t>(r)] == layer_[i] + 1) {
        stack.push_back(static_cast<std::size_t>(r));
      } else {
        ++next_edge_[i];
      }
    }
    return false;
  }

  const CandidateGraph& g_;
  std::vector<std::int32_t> row_match_;
  std::vector<std::int32_t> col_match_;
  std::vector<std::size_t> layer_;
  std::vector<std::size_t> next_edge_;
  std::vector<std::size_t> stack_;
};

}  // namespace

std::size_t maximum_matching_size(const CandidateGraph& graph) {
  if (graph.row_offsets.size() != graph.rows + 1) return 0;
  return HopcroftKarp(graph).run(0);
}

std::size_t maximum_matching(const CandidateGraph& graph, std::vector<std::int32_t>& row_to_col) {
  if (graph.row_offsets.size() != graph.rows + 1) return 0;
  HopcroftKarp matcher(graph);
  const std::size_t size = matcher.run(matcher.seed(row_to_col));
  row_to_col = matcher.row_match();
  return size;
}

}  // namespace springscan::analysis
