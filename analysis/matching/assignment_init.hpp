#pragma once
// Internal to the assignment solvers (assignment_dense.cpp, assignment_sparse.cpp): the
// Jonker-Volgenant "augmenting row reduction" warm start, written once for dense rows and for
// sparse candidate rows. R. Jonker, A. Volgenant, "A shortest augmenting path algorithm for
// dense and sparse linear assignment problems", Computing 38, 1987, section 4.2.
//
// Each free row bids for its cheapest column j1 (reduced by v), lowering v_j1 by the gap to its
// second cheapest, so that both become equally attractive; a displaced row bids again. It keeps
// the invariants the shortest-path phase and the certificate need (assignment.hpp):
//   * v only decreases, and only on columns that get (and keep) an owner: v <= 0, v = 0 on
//     unused columns;
//   * every assigned row's column minimises c_ij - v_j over the row.
// Afterwards u_i = min_j (c_ij - v_j) for every row, so all reduced costs are >= 0.

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <vector>

#include "analysis/matching/assignment.hpp"

namespace springscan::analysis::detail {

/// `scan_row(i, visit)` calls visit(j, c_ij) for every edge of row i.
/// Returns false (and leaves `a` to be reset by the caller) if rounding broke the invariants.
/// Longer than our usual 60 lines on purpose: it is Jonker and Volgenant's augmenting row
/// reduction step by step, and split into pieces it no longer reads against the paper.
template <class ScanRow>
bool augmenting_row_reduction(std::size_t rows, const ScanRow& scan_row, Assignment& a,
                              int passes = 2) {
  constexpr double kInf = std::numeric_limits<double>::infinity();
  std::vector<std::int32_t> free_rows;
  for (std::size_t i = 0; i < rows; ++i) {
    if (a.row_to_col[i] < 0) free_rows.push_back(static_cast<std::int32_t>(i));
  }
  std::vector<std::int32_t> still_free;
  // Cap on bids per pass: each bid lowers a price, but near-ties can make many tiny steps.
  const std::size_t max_bids = 4 * rows + 16;
  for (int pass = 0; pass < passes && !free_rows.empty(); ++pass) {
    still_free.clear();
    std::size_t bids = 0;
    std::size_t k = 0;
    while (k < free_rows.size()) {
      const auto i = static_cast<std::size_t>(free_rows[k++]);
      double u1 = kInf, u2 = kInf;
      std::int32_t j1 = -1, j2 = -1;
      scan_row(i, [&](std::size_t j, double c) {
        const double h = c - a.v[j];
        if (h < u2) {
          if (h >= u1) {
            u2 = h;
            j2 = static_cast<std::int32_t>(j);
          } else {
            u2 = u1;
            j2 = j1;
            u1 = h;
            j1 = static_cast<std::int32_t>(j);
          }
        }
      });
      if (j1 < 0 || j2 < 0 || !(u2 < kInf)) {
        still_free.push_back(static_cast<std::int32_t>(i));  // fewer than two candidates
        continue;
      }
      std::int32_t owner = a.col_to_row[static_cast<std::size_t>(j1)];
      const bool strict = u1 < u2;
      if (strict) {
        a.v[static_cast<std::size_t>(j1)] -= u2 - u1;
      } else if (owner >= 0) {
        j1 = j2;  // a tie: take the equally cheap column instead of fighting over j1
        owner = a.col_to_row[static_cast<std::size_t>(j1)];
      }
      if (owner >= 0) a.row_to_col[static_cast<std::size_t>(owner)] = -1;
      a.row_to_col[i] = j1;
      a.col_to_row[static_cast<std::size_t>(j1)] = static_cast<std::int32_t>(i);
      if (owner < 0) continue;
      if (strict && ++bids < max_bids) {
        free_rows[--k] = owner;  // the displaced row bids again at once
      } else {
        still_free.push_back(owner);
      }
    }
    free_rows.swap(still_free);
  }
  // Row potentials: the row minimum. An assigned column attains it (up to rounding); if one
  // does not, the warm start is reported unusable and the caller starts over without it.
  for (std::size_t i = 0; i < rows; ++i) {
    double best = kInf;
    double own = kInf;
    const std::int32_t mine = a.row_to_col[i];
    scan_row(i, [&](std::size_t j, double c) {
      const double h = c - a.v[j];
      if (h < best) best = h;
      if (static_cast<std::int32_t>(j) == mine && h < own) own = h;
    });
    a.u[i] = best < kInf ? best : 0.0;
    if (mine >= 0 && !(own - best <= 1e-12 * (1.0 + std::abs(best)))) return false;
  }
  return true;
}

}  // namespace springscan::analysis::detail

namespace springscan::analysis::detail {

/// Square problems only (rows == cols): Bertsekas' forward auction with epsilon scaling
/// (D. P. Bertsekas, "The auction algorithm: a distributed relaxation method for the
/// assignment problem", Annals of OR 14, 1988; scaling: Bertsekas & Eckstein 1988). Each free
/// row bids for its cheapest column (c_ij - v_j), lowering v_j by the gap to the second
/// cheapest plus epsilon; epsilon shrinks by `theta` per phase down to `eps_final`. The result
/// is epsilon-optimal, not exact: it only warms up the potentials v, and the caller keeps the
/// rows whose column is (to rounding) their minimum and re-solves the rest exactly. Returns
/// false when the bid budget runs out (then `a` must be reset by the caller).
template <class ScanRow>
bool epsilon_scaling_auction(std::size_t n, const ScanRow& scan_row, double eps_start,
                             double eps_final, double theta, double lone_gap, std::size_t max_bids,
                             Assignment& a) {
  constexpr double kInf = std::numeric_limits<double>::infinity();
  std::vector<std::int32_t> queue;
  queue.reserve(n);
  std::size_t bids = 0;
  for (double eps = eps_start;; eps = std::max(eps / theta, eps_final)) {
    std::fill(a.row_to_col.begin(), a.row_to_col.end(), -1);
    std::fill(a.col_to_row.begin(), a.col_to_row.end(), -1);
    queue.clear();
    for (std::size_t i = n; i-- > 0;) queue.push_back(static_cast<std::int32_t>(i));
    while (!queue.empty()) {
      const auto i = static_cast<std::size_t>(queue.back());
      queue.pop_back();
      double w1 = kInf, w2 = kInf;
      std::int32_t j1 = -1;
      scan_row(i, [&](std::size_t j, double c) {
        const double h = c - a.v[j];
        if (h < w1) {
          w2 = w1;
          w1 = h;
          j1 = static_cast<std::int32_t>(j);
        } else if (h < w2) {
          w2 = h;
        }
      });
      if (j1 < 0 || ++bids > max_bids) return false;
      const double gap = w2 < kInf ? w2 - w1 : lone_gap;
      a.v[static_cast<std::size_t>(j1)] -= gap + eps;
      const std::int32_t owner = a.col_to_row[static_cast<std::size_t>(j1)];
      if (owner >= 0) {
        a.row_to_col[static_cast<std::size_t>(owner)] = -1;
        queue.push_back(owner);
      }
      a.row_to_col[i] = j1;
      a.col_to_row[static_cast<std::size_t>(j1)] = static_cast<std::int32_t>(i);
    }
    if (eps <= eps_final) return true;
  }
}

/// After a warm start that left some rows non-tight: u_i = min_j (c_ij - v_j), and rows whose
/// assigned column does not attain it (beyond rounding) are released.
template <class ScanRow>
void tighten_rows(std::size_t rows, const ScanRow& scan_row, Assignment& a) {
  constexpr double kInf = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < rows; ++i) {
    double best = kInf, own = kInf;
    const std::int32_t mine = a.row_to_col[i];
    scan_row(i, [&](std::size_t j, double c) {
      const double h = c - a.v[j];
      if (h < best) best = h;
      if (static_cast<std::int32_t>(j) == mine && h < own) own = h;
    });
    a.u[i] = best < kInf ? best : 0.0;
    if (mine >= 0 && !(own - best <= 1e-12 * (1.0 + std::abs(best)))) {
      a.col_to_row[static_cast<std::size_t>(mine)] = -1;
      a.row_to_col[i] = -1;
    }
  }
}

}  // namespace springscan::analysis::detail
