// Dense rectangular assignment by shortest augmenting paths (docs/matching.md "Dense solver").
// Warm start, then one shortest augmenting path search per row left free
// (assignment_dense_search.hpp). Square problems start from the Jonker-Volgenant column
// reduction and reduction transfer (R. Jonker, A. Volgenant, Computing 38, 1987, section 4.1)
// and shift v to v <= 0 at the end; rectangular ones start from v = 0 (row reduction), which
// keeps v_j <= 0 and v_j = 0 on unused columns throughout: the rectangular certificate.
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <string>

#include "analysis/matching/assignment.hpp"
#include "analysis/matching/assignment_dense_search.hpp"
#include "analysis/matching/assignment_init.hpp"

namespace springscan::analysis {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
using detail::Lanes;

// The problem's costs as rows of a matrix in memory. By slot, a row gathers through the
// slot -> column map (the matrix is not permuted: that would cost O(rows) per swap).
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
  struct SlotRow {
    const double* values;
    const std::int32_t* column;
    double operator()(std::size_t k) const { return values[column[k]]; }
    Lanes lanes(std::size_t k) const { return Lanes{values[column[k]], values[column[k + 1]]}; }
  };
  SlotRow row(std::size_t i, const std::int32_t* column) const {
    return {&m_.values[i * m_.cols], column};
  }
  void swap_slots(std::size_t, std::size_t) {}

 private:
  const DenseCostMatrix& m_;
};

// Squared distances computed on the fly (O(m + n) memory, no m x n matrix): cheaper than
// streaming a matrix, since the search reads every todo column of a row. Column coordinates
// are kept coordinate-wise, in column order for the warm start and in slot order (swapped
// along with the search's slots) for the search.
class PointCosts {
 public:
  PointCosts(const std::vector<Vec3>& rows, const std::vector<Vec3>& cols) : rows_(rows) {
    for (int c = 0; c < 3; ++c) {
      coords_[c].resize(cols.size());
      for (std::size_t j = 0; j < cols.size(); ++j) coords_[c][j] = cols[j][c];
      slots_[c] = coords_[c];
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
    Lanes lanes(std::size_t j) const {
      const Lanes dx = x - detail::load_lanes(xs + j);
      const Lanes dy = y - detail::load_lanes(ys + j);
      const Lanes dz = z - detail::load_lanes(zs + j);
      return dx * dx + dy * dy + dz * dz;
    }
  };
  Row row(std::size_t i) const { return make_row(i, coords_); }
  Row row(std::size_t i, const std::int32_t*) const { return make_row(i, slots_); }
  void swap_slots(std::size_t a, std::size_t b) {
    for (auto& c : slots_) std::swap(c[a], c[b]);
  }

 private:
  Row make_row(std::size_t i, const std::array<std::vector<double>, 3>& c) const {
    const Vec3& p = rows_[i];
    return {p.x(), p.y(), p.z(), c[0].data(), c[1].data(), c[2].data()};
  }
  const std::vector<Vec3>& rows_;
  std::array<std::vector<double>, 3> coords_;  ///< column order
  std::array<std::vector<double>, 3> slots_;   ///< slot order
};

// Rectangular warm start: u_i = min_j c_ij keeps every reduced cost >= 0 with v = 0; a row
// whose cheapest column is still free takes it.
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

// Square warm start, Jonker-Volgenant section 4.1: v_j = min_i c_ij (column reduction; the
// column goes to its cheapest row unless that row already holds a cheaper column), then
// "reduction transfer": a row holding one column lowers that column's v by its second best
// reduced cost, so that u_i can take it. Afterwards every reduced cost c_ij - v_j is >= 0 and
// each assigned row's column attains its row minimum, as augmenting_row_reduction requires.
template <class Costs>
void column_reduction(const Costs& costs, Assignment& a) {
  const std::size_t n = costs.cols();
  std::vector<double> low(n, kInf);
  std::vector<std::int32_t> arg(n, 0);
  for (std::size_t i = 0; i < costs.rows(); ++i) {  // row-wise: contiguous for a matrix
    const auto row = costs.row(i);
    for (std::size_t j = 0; j < n; ++j) {
      const double c = row(j);
      if (c < low[j]) {
        low[j] = c;
        arg[j] = static_cast<std::int32_t>(i);
      }
    }
  }
  std::vector<int> matches(costs.rows(), 0);
  for (std::size_t j = n; j-- > 0;) {
    const auto i = static_cast<std::size_t>(arg[j]);
    a.v[j] = low[j];
    if (++matches[i] == 1) {
      a.row_to_col[i] = static_cast<std::int32_t>(j);
      a.col_to_row[j] = arg[j];
    } else if (low[j] < a.v[static_cast<std::size_t>(a.row_to_col[i])]) {
      a.col_to_row[static_cast<std::size_t>(a.row_to_col[i])] = -1;
      a.row_to_col[i] = static_cast<std::int32_t>(j);
      a.col_to_row[j] = arg[j];
    }
  }
  for (std::size_t i = 0; i < costs.rows(); ++i) {
    if (matches[i] != 1) continue;
    const auto own = static_cast<std::size_t>(a.row_to_col[i]);
    const auto row = costs.row(i);
    double second = kInf;
    for (std::size_t j = 0; j < n; ++j) {
      const double h = row(j) - a.v[j];
      if (j != own && h < second) second = h;
    }
    if (second < kInf) a.v[own] -= second;
  }
}

template <class Costs>
void reset(const Costs& costs, Assignment& a) {
  std::fill(a.row_to_col.begin(), a.row_to_col.end(), -1);
  std::fill(a.col_to_row.begin(), a.col_to_row.end(), -1);
  std::fill(a.u.begin(), a.u.end(), 0.0);
  std::fill(a.v.begin(), a.v.end(), 0.0);
  row_reduction(costs, a);
}

template <class Costs>
Expected<Assignment> solve_with(Costs& costs) {
  Assignment a;
  a.row_to_col.assign(costs.rows(), -1);
  a.col_to_row.assign(costs.cols(), -1);
  a.u.assign(costs.rows(), 0.0);
  a.v.assign(costs.cols(), 0.0);
  if (costs.rows() == 0) return a;

  // Warm start. augmenting_row_reduction with no bidding passes only sets u_i to the row
  // minimum of c_ij - v_j and checks that each assigned column attains it. Its bidding
  // passes (assignment_init.hpp) do not pay off here: on the bench_matching instances they
  // halve the rows left for the search but cost more than the searches they save (n = 1000:
  // 15 ms without, 17 ms with one pass, 19 ms with two).
  const bool square = costs.rows() == costs.cols();
  if (square) {
    column_reduction(costs, a);
  } else {
    row_reduction(costs, a);
  }
  const auto scan_row = [&costs](std::size_t i, auto&& visit) {
    const auto row = costs.row(i);
    for (std::size_t j = 0; j < costs.cols(); ++j) visit(j, row(j));
  };
  if (!detail::augmenting_row_reduction(costs.rows(), scan_row, a, /*passes=*/0)) {
    reset(costs, a);
  }

  detail::SlotColumns slots(a.v);
  for (std::size_t i = 0; i < costs.rows(); ++i) {
    if (a.row_to_col[i] >= 0) continue;
    if (!detail::augment_from(costs, static_cast<std::int32_t>(i), a, slots)) {
      return fail("dense assignment: no augmenting path from row " + std::to_string(i));
    }
    ++a.augmentations;
  }
  slots.write_potentials(a.v);
  if (square) {
    // Square: every column is used, so (u + V, v - V) is an equally valid certificate; the
    // largest V with v <= 0 is max v.
    const double shift = *std::max_element(a.v.begin(), a.v.end());
    for (double& x : a.v) x -= shift;
    for (double& x : a.u) x += shift;
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
      return fail("dense assignment: cost at row " + std::to_string(k / cost.cols) + ", column " +
                  std::to_string(k % cost.cols) + " is not finite");
    }
  }
  MatrixCosts costs(cost);
  return solve_with(costs);
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
  PointCosts costs(rows, cols);
  return solve_with(costs);
}

}  // namespace springscan::analysis
