#pragma once
// Exact minimum-cost rectangular assignment (paper section 5: the one-to-one correspondences
// between the k-center-reduced model P and scan Q; the paper used LEDA, we solve it ourselves).
//
// Problem: rows R (|R| = m) and columns C (|C| = n), m <= n. Find x assigning every row to a
// distinct column minimising sum c_ij. LP dual (docs/matching.md):
//     max  sum_i u_i + sum_j v_j   s.t.  u_i + v_j <= c_ij  (every edge),  v_j <= 0.
// A matching x with duals (u, v) is optimal iff (certificate):
//   primal feasibility     every row matched, no column used twice, only existing edges;
//   dual feasibility       u_i + v_j <= c_ij on every edge, v_j <= 0 on every column;
//   complementary slackness u_i + v_j = c_ij on matched edges, v_j = 0 on unmatched columns.
// Both solvers below keep these invariants, so every result carries its own proof.
//
// Thread safety: every function is pure; concurrent calls on distinct outputs are safe.

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "analysis/core/expected.hpp"
#include "analysis/core/point_cloud.hpp"

namespace springscan::analysis {

/// A dense m x n cost matrix, row-major (values[i * cols + j] = c_ij). Costs must be finite.
struct DenseCostMatrix {
  std::size_t rows = 0;
  std::size_t cols = 0;
  std::vector<double> values;
  double at(std::size_t i, std::size_t j) const { return values[i * cols + j]; }
};

/// A sparse bipartite graph in compressed-row form: the edges of row i are
/// cols[row_offsets[i] .. row_offsets[i + 1]) with costs at the same positions.
struct CandidateGraph {
  std::size_t rows = 0;
  std::size_t cols = 0;
  std::vector<std::size_t> row_offsets;  ///< rows + 1 entries, non-decreasing, starts at 0
  std::vector<std::int32_t> col_index;   ///< column of each edge, in [0, cols)
  std::vector<double> costs;             ///< cost of each edge, finite
  std::size_t edge_count() const { return col_index.size(); }
};

/// A row-saturating assignment with its dual potentials (the optimality certificate).
struct Assignment {
  std::vector<std::int32_t> row_to_col;  ///< column of each row (-1 only if infeasible)
  std::vector<std::int32_t> col_to_row;  ///< row of each column, -1 when unused
  std::vector<double> u;                 ///< row potentials
  std::vector<double> v;                 ///< column potentials, all <= 0
  double total_cost = 0.0;               ///< sum of the matched costs
  std::size_t augmentations = 0;         ///< shortest augmenting paths run (after warm start)
};

/// Dense shortest augmenting path solver (Jonker-Volgenant family; the rectangular variant of
/// Crouse 2016, as in scipy.optimize.linear_sum_assignment) with a row-reduction warm start.
/// O(m^2 n) worst case, O(n) memory beyond the matrix. Errors: rows > cols, size mismatch,
/// non-finite cost (named with its row and column).
Expected<Assignment> solve_dense(const DenseCostMatrix& cost);

/// The same solver on c_ij = |rows[i] - cols[j]|^2 (mm^2), computed on the fly: O(m + n)
/// memory, so it also serves as the fallback for large point sets. Errors: more rows than
/// columns, a non-finite coordinate.
Expected<Assignment> solve_dense_points(const std::vector<Vec3>& rows,
                                        const std::vector<Vec3>& cols);

/// Successive shortest paths on a sparse graph: Dijkstra with a binary heap on reduced costs
/// c_ij - u_i - v_j >= 0, one augmentation per row. O(m (E + n) log n) worst case; on
/// geometric candidate graphs each search stays local. Exact on the given graph. Errors:
/// malformed graph, or no row-saturating matching exists (the row that could not be placed).
Expected<Assignment> solve_sparse(const CandidateGraph& graph);

/// Size of a maximum cardinality matching of the graph (Hopcroft-Karp, O(E sqrt(V))): the
/// feasibility check before solve_sparse; the graph is feasible iff this equals graph.rows.
std::size_t maximum_matching_size(const CandidateGraph& graph);

/// The same, continuing from a matching: `row_to_col` holds a column per row or -1 (entries
/// that are not an edge of their row or reuse a column are dropped) and receives a maximum
/// matching. Widening a candidate graph keeps the previous matching valid, so each round only
/// adds the missing augmentations. Returns the matching's size.
std::size_t maximum_matching(const CandidateGraph& graph, std::vector<std::int32_t>& row_to_col);

/// The outcome of a certificate check: ok, or the first violated condition with its numbers.
struct CertificateCheck {
  bool ok = false;
  double max_dual_violation = 0.0;  ///< max over edges of u_i + v_j - c_ij (<= tol when ok)
  double max_matched_slack = 0.0;   ///< max over matched edges of |c_ij - u_i - v_j|
  double duality_gap = 0.0;         ///< |total_cost - (sum u + sum v)|
  std::string failure;              ///< empty when ok
};

/// Checks the certificate against every pair of a dense matrix. `tolerance` is absolute, in
/// cost units (use ~1e-9 x the largest cost magnitude).
CertificateCheck check_certificate(const DenseCostMatrix& cost, const Assignment& assignment,
                                   double tolerance);

/// Checks the certificate against every edge of a sparse graph (optimality on that graph).
CertificateCheck check_certificate(const CandidateGraph& graph, const Assignment& assignment,
                                   double tolerance);

}  // namespace springscan::analysis
