// The dense and sparse assignment solvers against brute force and their own dual certificate.
#include "analysis/matching/assignment.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <limits>
#include <numeric>
#include <random>

#include "tests/analysis/assignment_brute_force.hpp"

namespace springscan::analysis {
namespace {

constexpr double kTol = 1e-9;

DenseCostMatrix random_matrix(std::size_t rows, std::size_t cols, std::uint32_t seed,
                              double max_cost = 100.0) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, max_cost);
  DenseCostMatrix m{rows, cols, std::vector<double>(rows * cols)};
  for (auto& x : m.values) x = u(rng);
  return m;
}

// Squared distances between two random point sets in a 100 mm cube: the costs of the paper.
DenseCostMatrix squared_distances(std::size_t rows, std::size_t cols, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 100.0);
  std::vector<std::array<double, 3>> p(rows), q(cols);
  for (auto& x : p) x = {u(rng), u(rng), u(rng)};
  for (auto& x : q) x = {u(rng), u(rng), u(rng)};
  DenseCostMatrix m{rows, cols, std::vector<double>(rows * cols)};
  for (std::size_t i = 0; i < rows; ++i) {
    for (std::size_t j = 0; j < cols; ++j) {
      double d = 0.0;
      for (int k = 0; k < 3; ++k) d += (p[i][k] - q[j][k]) * (p[i][k] - q[j][k]);
      m.values[i * cols + j] = d;
    }
  }
  return m;
}

// The graph of every finite entry of `m` (infinite = no edge).
CandidateGraph graph_of(const DenseCostMatrix& m) {
  CandidateGraph g{m.rows, m.cols, {0}, {}, {}};
  for (std::size_t i = 0; i < m.rows; ++i) {
    for (std::size_t j = 0; j < m.cols; ++j) {
      if (m.at(i, j) < std::numeric_limits<double>::infinity()) {
        g.col_index.push_back(static_cast<std::int32_t>(j));
        g.costs.push_back(m.at(i, j));
      }
    }
    g.row_offsets.push_back(g.col_index.size());
  }
  return g;
}

void expect_certified(const DenseCostMatrix& m, const Assignment& a) {
  const CertificateCheck check = check_certificate(m, a, kTol * 1e4);
  EXPECT_TRUE(check.ok) << check.failure;
}

TEST(DenseAssignment, MatchesBruteForceUpToEight) {
  std::uint32_t seed = 1;
  for (std::size_t cols = 1; cols <= 8; ++cols) {
    for (std::size_t rows = 1; rows <= cols; ++rows) {
      const DenseCostMatrix m = random_matrix(rows, cols, seed++);
      const auto a = solve_dense(m);
      ASSERT_TRUE(a.ok()) << a.message();
      EXPECT_NEAR(a->total_cost, testing::brute_force_cost(m), kTol) << rows << "x" << cols;
      expect_certified(m, *a);
    }
  }
}

TEST(DenseAssignment, CertificateOnRandomSquaredDistances) {
  for (const auto& [rows, cols] : {std::pair{150u, 150u}, {120u, 200u}, {37u, 301u}}) {
    const DenseCostMatrix m = squared_distances(rows, cols, rows * 7 + cols);
    const auto a = solve_dense(m);
    ASSERT_TRUE(a.ok()) << a.message();
    expect_certified(m, *a);
  }
}

TEST(DenseAssignment, TiesAndDuplicatesStayOptimal) {
  // All costs equal: any injection is optimal.
  DenseCostMatrix flat{6, 9, std::vector<double>(54, 3.0)};
  auto a = solve_dense(flat);
  ASSERT_TRUE(a.ok());
  EXPECT_DOUBLE_EQ(a->total_cost, 18.0);
  expect_certified(flat, *a);
  // Small integer costs: many ties between different optima.
  std::mt19937 rng(5);
  std::uniform_int_distribution<int> die(0, 2);
  DenseCostMatrix ints{7, 8, std::vector<double>(56)};
  for (auto& x : ints.values) x = die(rng);
  a = solve_dense(ints);
  ASSERT_TRUE(a.ok());
  EXPECT_DOUBLE_EQ(a->total_cost, testing::brute_force_cost(ints));
  expect_certified(ints, *a);
  // Identical rows (duplicate model points) and identical columns (duplicate scan points).
  DenseCostMatrix dup = random_matrix(6, 8, 9);
  for (std::size_t j = 0; j < 8; ++j) dup.values[1 * 8 + j] = dup.values[0 * 8 + j];
  for (std::size_t i = 0; i < 6; ++i) dup.values[i * 8 + 5] = dup.values[i * 8 + 2];
  a = solve_dense(dup);
  ASSERT_TRUE(a.ok());
  EXPECT_NEAR(a->total_cost, testing::brute_force_cost(dup), kTol);
  expect_certified(dup, *a);
}

TEST(DenseAssignment, EmptyAndSingle) {
  auto a = solve_dense(DenseCostMatrix{});
  ASSERT_TRUE(a.ok());
  EXPECT_TRUE(a->row_to_col.empty());
  EXPECT_EQ(a->total_cost, 0.0);
  a = solve_dense(DenseCostMatrix{0, 4, {}});
  ASSERT_TRUE(a.ok());
  EXPECT_EQ(a->v.size(), 4u);
  a = solve_dense(DenseCostMatrix{1, 1, {2.5}});
  ASSERT_TRUE(a.ok());
  EXPECT_EQ(a->row_to_col[0], 0);
  EXPECT_DOUBLE_EQ(a->total_cost, 2.5);
  a = solve_dense(DenseCostMatrix{1, 4, {4, 3, 1, 2}});
  ASSERT_TRUE(a.ok());
  EXPECT_EQ(a->row_to_col[0], 2);
}

TEST(DenseAssignment, RejectsBadInput) {
  EXPECT_FALSE(solve_dense(DenseCostMatrix{3, 2, std::vector<double>(6, 1.0)}).ok());
  EXPECT_FALSE(solve_dense(DenseCostMatrix{2, 2, {1, 2, 3}}).ok());
  const auto nan =
      solve_dense(DenseCostMatrix{2, 2, {1, std::numeric_limits<double>::quiet_NaN(), 3, 4}});
  ASSERT_FALSE(nan.ok());
  EXPECT_NE(nan.message().find("row 0, column 1"), std::string::npos) << nan.message();
}

TEST(DenseAssignment, CertificateCatchesWrongAnswers) {
  const DenseCostMatrix m = random_matrix(5, 6, 3);
  auto a = solve_dense(m);
  ASSERT_TRUE(a.ok());
  Assignment swapped = *a;  // a different, feasible but (generically) worse assignment
  std::swap(swapped.row_to_col[0], swapped.row_to_col[1]);
  swapped.col_to_row[static_cast<std::size_t>(swapped.row_to_col[0])] = 0;
  swapped.col_to_row[static_cast<std::size_t>(swapped.row_to_col[1])] = 1;
  EXPECT_FALSE(check_certificate(m, swapped, kTol).ok);
  Assignment raised = *a;  // duals that overstate the bound
  raised.u[2] += 1.0;
  EXPECT_FALSE(check_certificate(m, raised, kTol).ok);
}

TEST(SparseAssignment, MatchesBruteForceOnSparseGraphs) {
  std::mt19937 rng(11);
  std::bernoulli_distribution keep(0.5);
  int solved = 0;
  for (std::uint32_t trial = 0; trial < 60; ++trial) {
    const std::size_t cols = 3 + trial % 6;
    const std::size_t rows = 1 + trial % cols;
    DenseCostMatrix m = random_matrix(rows, cols, 100 + trial);
    for (auto& x : m.values) {
      if (!keep(rng)) x = std::numeric_limits<double>::infinity();
    }
    const double best = testing::brute_force_cost(m);
    const CandidateGraph g = graph_of(m);
    const auto a = solve_sparse(g);
    const bool feasible = best < std::numeric_limits<double>::infinity();
    EXPECT_EQ(maximum_matching_size(g) == rows, feasible);
    ASSERT_EQ(a.ok(), feasible) << (a.ok() ? "" : a.message());
    if (!feasible) continue;
    ++solved;
    EXPECT_NEAR(a->total_cost, best, kTol);
    const CertificateCheck check = check_certificate(g, *a, kTol * 1e4);
    EXPECT_TRUE(check.ok) << check.failure;
  }
  EXPECT_GT(solved, 10);
}

TEST(SparseAssignment, AgreesWithDenseOnCompleteGraph) {
  const DenseCostMatrix m = squared_distances(90, 130, 21);
  const auto dense = solve_dense(m);
  const auto sparse = solve_sparse(graph_of(m));
  ASSERT_TRUE(dense.ok() && sparse.ok());
  EXPECT_NEAR(sparse->total_cost, dense->total_cost, 1e-9 * dense->total_cost);
  expect_certified(m, *sparse);
}

TEST(SparseAssignment, InfeasibleGraphIsReported) {
  // Rows 0, 1 and 2 can only use columns 0 and 1: no row-saturating matching.
  CandidateGraph g{3, 4, {0, 2, 4, 5}, {0, 1, 0, 1, 1}, {1, 2, 3, 4, 5}};
  EXPECT_EQ(maximum_matching_size(g), 2u);
  const auto a = solve_sparse(g);
  ASSERT_FALSE(a.ok());
  EXPECT_NE(a.message().find("no row-saturating matching"), std::string::npos);
}

TEST(SparseAssignment, MaximumMatchingContinuesFromASeed) {
  std::mt19937 rng(31);
  std::bernoulli_distribution keep(0.3);
  for (std::uint32_t trial = 0; trial < 20; ++trial) {
    DenseCostMatrix m = random_matrix(12, 14, 300 + trial);
    for (auto& x : m.values) {
      if (!keep(rng)) x = std::numeric_limits<double>::infinity();
    }
    const CandidateGraph g = graph_of(m);
    // A seed with a valid pair, a pair that is not an edge, a reused column and junk.
    std::vector<std::int32_t> matching(12, -1);
    if (g.row_offsets[1] > g.row_offsets[0]) matching[0] = g.col_index[0];
    for (std::int32_t j = 0; j < 14; ++j) {
      if (!(m.at(1, static_cast<std::size_t>(j)) < std::numeric_limits<double>::infinity())) {
        matching[1] = j;
      }
    }
    matching[2] = matching[0];
    matching[3] = 99;
    const std::size_t size = maximum_matching(g, matching);
    EXPECT_EQ(size, maximum_matching_size(g));
    std::vector<int> used(14, 0);
    std::size_t matched = 0;
    for (std::size_t i = 0; i < 12; ++i) {
      const std::int32_t j = matching[i];
      if (j < 0) continue;
      ++matched;
      ASSERT_LT(j, 14);
      EXPECT_LT(m.at(i, static_cast<std::size_t>(j)), std::numeric_limits<double>::infinity());
      EXPECT_EQ(++used[static_cast<std::size_t>(j)], 1);
    }
    EXPECT_EQ(matched, size);
  }
}

TEST(SparseAssignment, EmptySingleAndMalformed) {
  auto a = solve_sparse(CandidateGraph{0, 0, {0}, {}, {}});
  ASSERT_TRUE(a.ok());
  EXPECT_EQ(maximum_matching_size(CandidateGraph{0, 0, {0}, {}, {}}), 0u);
  a = solve_sparse(CandidateGraph{1, 3, {0, 2}, {2, 1}, {5.0, 7.0}});
  ASSERT_TRUE(a.ok());
  EXPECT_EQ(a->row_to_col[0], 2);
  EXPECT_DOUBLE_EQ(a->total_cost, 5.0);
  EXPECT_FALSE(solve_sparse(CandidateGraph{1, 3, {0, 1}, {3}, {1.0}}).ok());  // column 3
  EXPECT_FALSE(solve_sparse(CandidateGraph{1, 3, {0, 2}, {0}, {1.0}}).ok());  // sizes
  EXPECT_FALSE(solve_sparse(CandidateGraph{2, 1, {0, 1, 2}, {0, 0}, {1, 1}}).ok());
}

}  // namespace
}  // namespace springscan::analysis
