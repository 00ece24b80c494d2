#pragma once
// The oracle of the assignment tests (STYLE.md section 8): the cheapest injection of rows into
// columns, by trying every permutation of the columns. For n <= 8 or so.

#include <algorithm>
#include <limits>
#include <numeric>
#include <vector>

#include "analysis/matching/assignment.hpp"

namespace springscan::analysis::testing {

/// The least total cost of an assignment of every row to a distinct column (the first `rows`
/// entries of each column permutation). Infinite costs mark missing edges.
inline double brute_force_cost(const DenseCostMatrix& m) {
  std::vector<std::size_t> perm(m.cols);
  std::iota(perm.begin(), perm.end(), 0);
  double best = std::numeric_limits<double>::infinity();
  do {
    double c = 0.0;
    for (std::size_t i = 0; i < m.rows; ++i) c += m.at(i, perm[i]);
    best = std::min(best, c);
  } while (std::next_permutation(perm.begin(), perm.end()));
  return best;
}

}  // namespace springscan::analysis::testing
