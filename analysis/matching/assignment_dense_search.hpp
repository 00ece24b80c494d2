#pragma once
// Internal to assignment_dense.cpp: the shortest augmenting path search of the dense solver
// (docs/matching.md "Dense solver"), the rectangular Jonker-Volgenant variant of D. F. Crouse,
// "On implementing 2D rectangular assignment algorithms", IEEE TAES 52(4), 2016, Algorithm 1.
//
// Why it looks like this: nearly all of the solver's time is the Dijkstra inner loop, which
// relaxes every column not yet finalised (the "todo" set) from the row just reached and then
// finds the smallest tentative distance. Columns live in *slots*: slots [0, todo) are the todo
// set, [todo, n) the finalised columns in reverse order of finalisation. Everything the loop
// reads per column (potential v, distance, and the column's coordinates for point costs) is
// stored in slot order, so the loop streams contiguous arrays two doubles at a time (SSE2
// lanes via GCC vector extensions, the x86-64 baseline) instead of gathering through an index
// list; finalising a column swaps two slots. The slot order carries over between searches (it
// is just a permutation). The loop keeps no predecessors and finds the minimum's slot through
// per-block minima: both would otherwise cost as much as the relaxation itself.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <utility>
#include <vector>

#include "analysis/matching/assignment.hpp"

namespace springscan::analysis::detail {

/// Two doubles, one SSE2 register (16 bytes: no ABI change on x86-64 without AVX).
using Lanes = double __attribute__((vector_size(16)));
/// Slots per block of the relaxation: the minimum of each block is kept, so that finding the
/// slot of the minimum is a scan over n / 16 block minima plus one block.
constexpr std::size_t kBlock = 16;

inline Lanes load_lanes(const double* p) {
  Lanes x;
  std::memcpy(&x, p, sizeof x);
  return x;
}

/// Per-column state of the search, in slot order (see the file comment), and the rows the
/// current search has reached.
struct SlotColumns {
  std::vector<std::int32_t> column;  ///< column held by each slot
  std::vector<double> v;             ///< column potential
  std::vector<double> dist;          ///< tentative shortest reduced path cost
  std::vector<std::int32_t> rows;    ///< rows reached, in order (rows[0] = start)
  std::vector<double> bases;         ///< path length to each reached row minus its u
  std::vector<double> block_low;     ///< minimum distance of each block of kBlock slots

  explicit SlotColumns(const std::vector<double>& potentials)
      : column(potentials.size()),
        v(potentials),
        dist(potentials.size()),
        block_low(potentials.size() / kBlock + 1) {
    for (std::size_t j = 0; j < column.size(); ++j) column[j] = static_cast<std::int32_t>(j);
  }
  template <class SlotCosts>
  void swap_slots(std::size_t a, std::size_t b, SlotCosts& costs) {
    std::swap(column[a], column[b]);
    std::swap(v[a], v[b]);
    std::swap(dist[a], dist[b]);
    costs.swap_slots(a, b);
  }
  /// Potentials back in column order.
  void write_potentials(std::vector<double>& out) const {
    for (std::size_t k = 0; k < column.size(); ++k) out[static_cast<std::size_t>(column[k])] = v[k];
  }
};

/// Relaxes the todo slots from a row (d_k = min(d_k, base + c_k - v_k), base = path length to
/// the row minus its u), records each block's minimum in s.block_low and returns the smallest
/// tentative distance. `row` gives costs by slot: row(k) one, row.lanes(k) slots k and k + 1.
/// No predecessor is stored: that would double the loop's work (a compare and two blends per
/// pair on SSE2), while the few columns on the final path can find theirs afterwards
/// (find_predecessor). Scalar and lane code do the same operations in the same order, so a
/// slot's result does not depend on which path computed it.
template <class Row>
double relax_todo(const Row& row, double base, std::size_t todo, SlotColumns& s) {
  constexpr double kInf = std::numeric_limits<double>::infinity();
  const Lanes base2 = {base, base};
  double* dist = s.dist.data();
  const double* v = s.v.data();
  double lowest = kInf;
  std::size_t k = 0;
  for (std::size_t b = 0; k + kBlock <= todo; ++b) {
    Lanes low_a = {kInf, kInf};  // two pairs per step: independent minima keep both SSE
    Lanes low_b = low_a;         // units busy; `x < y ? x : y` is exactly minpd
    for (const std::size_t end = k + kBlock; k < end; k += 4) {
      const Lanes r_a = base2 + row.lanes(k) - load_lanes(v + k);
      const Lanes r_b = base2 + row.lanes(k + 2) - load_lanes(v + k + 2);
      Lanes d_a = load_lanes(dist + k);
      Lanes d_b = load_lanes(dist + k + 2);
      d_a = r_a < d_a ? r_a : d_a;
      d_b = r_b < d_b ? r_b : d_b;
      std::memcpy(dist + k, &d_a, sizeof d_a);
      std::memcpy(dist + k + 2, &d_b, sizeof d_b);
      low_a = d_a < low_a ? d_a : low_a;
      low_b = d_b < low_b ? d_b : low_b;
    }
    low_a = low_b < low_a ? low_b : low_a;
    s.block_low[b] = std::min(low_a[0], low_a[1]);
    lowest = std::min(lowest, s.block_low[b]);
  }
  double tail_low = kInf;  // the last, partial block
  for (; k < todo; ++k) {
    const double r = base + row(k) - v[k];
    dist[k] = r < dist[k] ? r : dist[k];
    tail_low = std::min(tail_low, dist[k]);
  }
  if (todo % kBlock != 0) s.block_low[todo / kBlock] = tail_low;
  return std::min(lowest, tail_low);
}

/// The todo slot to finalise next: one at distance `lowest`, a free column first (the path
/// ends there, Crouse's tie rule). Only blocks whose minimum is `lowest` are searched.
inline std::size_t pick_slot(double lowest, std::size_t todo, const SlotColumns& s,
                             const std::vector<std::int32_t>& col_to_row) {
  std::size_t first = todo;
  const std::size_t blocks = (todo + kBlock - 1) / kBlock;
  for (std::size_t b = 0; b < blocks; ++b) {
    if (s.block_low[b] != lowest) continue;
    for (std::size_t k = b * kBlock; k < std::min(todo, (b + 1) * kBlock); ++k) {
      if (s.dist[k] != lowest) continue;
      if (col_to_row[static_cast<std::size_t>(s.column[k])] < 0) return k;
      if (first == todo) first = k;
    }
  }
  return first;
}

/// The predecessor of the column finalised t-th (slot n - 1 - t): among the rows reached up
/// to then (s.rows[0..t]), the first whose relaxation gives its distance, i.e. a row with
/// d = base + c - v (exactly, as relax_todo computed it; the nearest one should rounding ever
/// differ). Returns an index into s.rows.
template <class SlotCosts>
std::size_t find_predecessor(const SlotCosts& costs, std::size_t t, const SlotColumns& s) {
  const std::size_t k = s.column.size() - 1 - t;
  std::size_t best = 0;
  double best_gap = std::numeric_limits<double>::infinity();
  for (std::size_t r = 0; r <= t; ++r) {
    const auto row = costs.row(static_cast<std::size_t>(s.rows[r]), s.column.data());
    const double gap = std::abs(s.bases[r] + row(k) - s.v[k] - s.dist[k]);
    if (gap < best_gap) {
      best = r;
      best_gap = gap;
      if (gap == 0.0) break;
    }
  }
  return best;
}

/// One search from free row `start` (Crouse, Algorithm 1 lines 9-27), the dual update that
/// keeps matched pairs tight and all reduced costs >= 0 (lines 28-33), and the augmentation.
/// a.v is not used: the potentials live in `s.v`. Returns false if no free column is
/// reachable (impossible for finite costs with rows <= cols).
template <class SlotCosts>
bool augment_from(SlotCosts& costs, std::int32_t start, Assignment& a, SlotColumns& s) {
  constexpr double kInf = std::numeric_limits<double>::infinity();
  const std::size_t n = s.column.size();
  std::fill(s.dist.begin(), s.dist.end(), kInf);
  s.rows.clear();
  s.bases.clear();
  std::size_t todo = n;
  double min_val = 0.0;
  std::int32_t i = start;
  while (true) {
    const auto row = costs.row(static_cast<std::size_t>(i), s.column.data());
    s.rows.push_back(i);
    s.bases.push_back(min_val - a.u[static_cast<std::size_t>(i)]);
    const double lowest = relax_todo(row, s.bases.back(), todo, s);
    if (!(lowest < kInf)) return false;
    min_val = lowest;
    const std::size_t next = pick_slot(lowest, todo, s, a.col_to_row);
    --todo;
    s.swap_slots(next, todo, costs);
    const std::int32_t owner = a.col_to_row[static_cast<std::size_t>(s.column[todo])];
    if (owner < 0) break;  // slot `todo` holds the sink
    i = owner;
  }
  // Flip the path: the sink was finalised last (t = n - 1 - todo); each column's predecessor
  // row s.rows[p] was reached through the column finalised at t = p - 1.
  const std::size_t last = n - 1 - todo;
  for (std::size_t t = last;;) {
    const std::size_t p = find_predecessor(costs, t, s);
    const std::int32_t j = s.column[n - 1 - t];
    const std::int32_t r = s.rows[p];
    a.row_to_col[static_cast<std::size_t>(r)] = j;
    a.col_to_row[static_cast<std::size_t>(j)] = r;
    if (p == 0) break;
    t = p - 1;
  }
  // Dual update: the column finalised t-th led to row s.rows[t + 1]; the sink (t = last) to
  // none. v_sink does not change (its distance is min_val).
  a.u[static_cast<std::size_t>(start)] += min_val;
  for (std::size_t t = 0; t < last; ++t) {
    const std::size_t k = n - 1 - t;
    const double delta = min_val - s.dist[k];
    s.v[k] -= delta;
    a.u[static_cast<std::size_t>(s.rows[t + 1])] += delta;
  }
  return true;
}

}  // namespace springscan::analysis::detail
