// The dense solver's fast paths (assignment_dense.cpp, assignment_dense_search.hpp): costs by
// slot in SSE2 lanes with a scalar tail, block minima, predecessors found after the search,
// the square Jonker-Volgenant warm start and its final shift of v. Checked against brute
// force, against the sparse solver on the complete graph (a different search: binary heap,
// stored predecessors) and against optima the tests construct.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <random>
#include <utility>

#include "analysis/matching/assignment.hpp"
#include "tests/analysis/assignment_brute_force.hpp"
#include "tests/analysis/synthetic.hpp"

namespace springscan::analysis {
namespace {

DenseCostMatrix squared_distances(const std::vector<Vec3>& rows, const std::vector<Vec3>& cols) {
  DenseCostMatrix m{rows.size(), cols.size(), std::vector<double>(rows.size() * cols.size())};
  for (std::size_t i = 0; i < rows.size(); ++i) {
    for (std::size_t j = 0; j < cols.size(); ++j) {
      m.values[i * cols.size() + j] = (rows[i] - cols[j]).squaredNorm();
    }
  }
  return m;
}

CandidateGraph complete_graph(const DenseCostMatrix& m) {
  CandidateGraph g{m.rows, m.cols, {0}, {}, m.values};
  for (std::size_t i = 0; i < m.rows; ++i) {
    for (std::size_t j = 0; j < m.cols; ++j) g.col_index.push_back(static_cast<std::int32_t>(j));
    g.row_offsets.push_back(g.col_index.size());
  }
  return g;
}

double largest(const DenseCostMatrix& m) {
  return std::max(1.0, *std::max_element(m.values.begin(), m.values.end()));
}

// The certificate against every entry (tolerance relative to the largest cost) and, for
// square problems, the optimum of the independent sparse solver.
void expect_optimal(const DenseCostMatrix& m, const Assignment& a, const char* what) {
  const double tol = 1e-9 * largest(m);
  const CertificateCheck check = check_certificate(m, a, tol);
  EXPECT_TRUE(check.ok) << what << " " << m.rows << "x" << m.cols << ": " << check.failure;
  const auto sparse = solve_sparse(complete_graph(m));
  ASSERT_TRUE(sparse.ok()) << sparse.message();
  EXPECT_NEAR(a.total_cost, sparse->total_cost, 1e-9 * std::max(1.0, sparse->total_cost))
      << what << " " << m.rows << "x" << m.cols;
}

TEST(DenseSolver, PointsAndMatrixAgreeAcrossLaneAndBlockBoundaries) {
  // Sizes around the 2-slot lanes, 4-slot steps and 16-slot blocks, square and rectangular.
  const std::pair<std::size_t, std::size_t> shapes[] = {
      {1, 1},   {2, 2},   {3, 3},   {4, 5},   {7, 7},   {8, 8},   {15, 15},  {16, 16},
      {17, 17}, {31, 33}, {33, 33}, {47, 48}, {64, 64}, {65, 65}, {80, 130}, {101, 101}};
  std::uint32_t seed = 40;
  for (const auto& [rows, cols] : shapes) {
    const auto p = testing::uniform_points(rows, seed++);
    const auto q = testing::uniform_points(cols, seed++);
    const DenseCostMatrix m = squared_distances(p, q);
    const auto by_points = solve_dense_points(p, q);
    const auto by_matrix = solve_dense(m);
    ASSERT_TRUE(by_points.ok() && by_matrix.ok());
    expect_optimal(m, *by_points, "points");
    expect_optimal(m, *by_matrix, "matrix");
    if (cols <= 8) {
      EXPECT_NEAR(by_points->total_cost, testing::brute_force_cost(m), 1e-9 * largest(m));
    }
  }
}

TEST(DenseSolver, TranslatedCopyIsMatchedToItself) {
  // Q = a permutation of P + t: for any permutation s, sum |p_i - p_s(i) - t|^2 =
  // sum |p_i - p_s(i)|^2 + n |t|^2 (the cross term sums to zero), so the optimum pairs each
  // point with its own translate at cost n |t|^2. On a unit grid with t half a spacing, many
  // paths tie.
  std::vector<Vec3> grid;
  for (int x = 0; x < 6; ++x) {
    for (int y = 0; y < 6; ++y) {
      for (int z = 0; z < 3; ++z) grid.emplace_back(x, y, z);
    }
  }
  const Vec3 t(0.5, 0.0, 0.25);
  std::vector<std::size_t> order(grid.size());
  std::iota(order.begin(), order.end(), 0);
  std::shuffle(order.begin(), order.end(), std::mt19937(3));
  std::vector<Vec3> scan;
  for (const std::size_t k : order) scan.push_back(grid[k] + t);
  const auto a = solve_dense_points(grid, scan);
  ASSERT_TRUE(a.ok()) << a.message();
  EXPECT_NEAR(a->total_cost, static_cast<double>(grid.size()) * t.squaredNorm(), 1e-9);
  for (std::size_t i = 0; i < grid.size(); ++i) {
    EXPECT_EQ(order[static_cast<std::size_t>(a->row_to_col[i])], i) << "model point " << i;
  }
  expect_optimal(squared_distances(grid, scan), *a, "grid");
}

TEST(DenseSolver, ExactTiesFromIntegerCostsAndDuplicatePoints) {
  std::mt19937 rng(8);
  std::uniform_int_distribution<int> die(0, 3);
  for (const auto& [rows, cols] : {std::pair{40u, 40u}, {30u, 45u}, {8u, 8u}}) {
    DenseCostMatrix m{rows, cols, std::vector<double>(rows * cols)};
    for (auto& x : m.values) x = die(rng);
    const auto a = solve_dense(m);
    ASSERT_TRUE(a.ok());
    expect_optimal(m, *a, "integer");
    if (cols <= 8) {
      EXPECT_EQ(a->total_cost, testing::brute_force_cost(m));
    }
  }
  // Every point twice in both sets: cost 0 is reachable and optimal.
  auto p = testing::uniform_points(20, 5);
  p.insert(p.end(), p.begin(), p.end());
  auto q = p;
  std::reverse(q.begin(), q.end());
  const auto a = solve_dense_points(p, q);
  ASSERT_TRUE(a.ok());
  EXPECT_EQ(a->total_cost, 0.0);
  expect_optimal(squared_distances(p, q), *a, "duplicates");
}

TEST(DenseSolver, SquareWarmStartShiftsPotentialsToTheRectangularForm) {
  // Large positive costs: column reduction sets v_j ~ 1e6; the returned v must still be
  // <= 0 (the certificate checks it) with the same optimum.
  std::mt19937 rng(12);
  std::uniform_real_distribution<double> u(0.0, 50.0);
  for (const std::size_t n : {6u, 37u}) {
    DenseCostMatrix m{n, n, std::vector<double>(n * n)};
    for (auto& x : m.values) x = 1e6 + u(rng);
    const auto a = solve_dense(m);
    ASSERT_TRUE(a.ok());
    EXPECT_LE(*std::max_element(a->v.begin(), a->v.end()), 0.0);
    expect_optimal(m, *a, "offset");
    if (n <= 8) {
      EXPECT_NEAR(a->total_cost, testing::brute_force_cost(m), 1e-6);
    }
  }
}

}  // namespace
}  // namespace springscan::analysis
