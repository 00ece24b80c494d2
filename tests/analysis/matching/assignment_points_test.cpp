// Point-set matching: dense and sparse paths agree, the global certificate holds, infeasible
// candidate graphs are widened or fall back to the dense solver.
#include "analysis/matching/assignment_points.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <limits>
#include <numeric>
#include <random>

#include "tests/analysis/synthetic.hpp"

namespace springscan::analysis {
namespace {

// Brute force over all injections of the model into the scan.
double brute_force(const std::vector<Vec3>& model, const std::vector<Vec3>& scan) {
  std::vector<std::size_t> perm(scan.size());
  std::iota(perm.begin(), perm.end(), 0);
  double best = std::numeric_limits<double>::infinity();
  do {
    double c = 0.0;
    for (std::size_t i = 0; i < model.size(); ++i) c += (model[i] - scan[perm[i]]).squaredNorm();
    best = std::min(best, c);
  } while (std::next_permutation(perm.begin(), perm.end()));
  return best;
}

void expect_consistent(const PointMatching& m, const std::vector<Vec3>& model,
                       const std::vector<Vec3>& scan) {
  EXPECT_TRUE(m.certified) << m.certificate.failure;
  ASSERT_EQ(m.model_to_scan.size(), model.size());
  std::vector<int> used(scan.size(), 0);
  double cost = 0.0;
  std::size_t matched = 0;
  for (std::size_t i = 0; i < model.size(); ++i) {
    const auto j = m.model_to_scan[i];
    if (j < 0) continue;
    ++matched;
    EXPECT_EQ(++used[static_cast<std::size_t>(j)], 1) << "scan point used twice";
    cost += (model[i] - scan[static_cast<std::size_t>(j)]).squaredNorm();
  }
  EXPECT_EQ(matched, std::min(model.size(), scan.size()));
  EXPECT_NEAR(cost, m.total_cost, 1e-9 * std::max(1.0, cost));
}

TEST(PointMatching, BruteForceSmallSets) {
  for (std::size_t n_model = 1; n_model <= 7; ++n_model) {
    for (std::size_t n_scan : {n_model, n_model + 1}) {
      const auto model = testing::uniform_points(n_model, static_cast<std::uint32_t>(n_model));
      const auto scan = testing::uniform_points(n_scan, static_cast<std::uint32_t>(50 + n_scan));
      const auto m = match_points(model, scan);
      ASSERT_TRUE(m.ok()) << m.message();
      EXPECT_NEAR(m->total_cost, brute_force(model, scan), 1e-9);
      expect_consistent(*m, model, scan);
    }
  }
}

TEST(PointMatching, MoreModelThanScanIsTransposed) {
  const auto model = testing::uniform_points(7, 3);
  const auto scan = testing::uniform_points(5, 4);
  const auto m = match_points(model, scan);
  ASSERT_TRUE(m.ok());
  EXPECT_FALSE(m->rows_are_model);
  EXPECT_NEAR(m->total_cost, brute_force(scan, model), 1e-9);
  expect_consistent(*m, model, scan);
}

TEST(PointMatching, SparseAgreesWithDense) {
  // Square (auction warm start), near-square (dummy rows, auction) and rectangular.
  for (const std::size_t n_scan : {400u, 405u, 430u}) {
    const auto model = testing::uniform_points(400, 5);
    const auto scan = testing::uniform_points(n_scan, 6);
    const auto dense = match_points(model, scan, {.dense_limit = 10'000});
    ASSERT_TRUE(dense.ok());
    EXPECT_TRUE(dense->used_dense);
    for (const int k : {1, 3, 10, 24}) {
      const auto sparse = match_points(model, scan, {.candidate_neighbors = k, .dense_limit = 100});
      ASSERT_TRUE(sparse.ok());
      EXPECT_FALSE(sparse->used_dense) << "k = " << k;
      // With one candidate per point the first solve is optimal only on that graph; pricing
      // or widening has to bring in the missing pairs.
      if (k == 1) {
        EXPECT_GT(sparse->pricing_rounds + sparse->widening_rounds, 0);
      }
      EXPECT_NEAR(sparse->total_cost, dense->total_cost, 1e-9 * dense->total_cost)
          << "k = " << k << ", scan " << n_scan;
      expect_consistent(*sparse, model, scan);
    }
  }
}

TEST(PointMatching, DuplicatesAndTies) {
  // Every scan point twice, model on a regular grid: many equal costs.
  std::vector<Vec3> model, scan;
  for (int x = 0; x < 12; ++x) {
    for (int y = 0; y < 12; ++y) {
      model.emplace_back(x, y, 0.0);
      scan.emplace_back(x + 0.5, y, 0.0);
      scan.emplace_back(x + 0.5, y, 0.0);
    }
  }
  const auto dense = match_points(model, scan, {.dense_limit = 10'000});
  const auto sparse = match_points(model, scan, {.candidate_neighbors = 2, .dense_limit = 10});
  ASSERT_TRUE(dense.ok() && sparse.ok());
  EXPECT_NEAR(dense->total_cost, 0.25 * 144, 1e-9);
  EXPECT_NEAR(sparse->total_cost, dense->total_cost, 1e-9);
  expect_consistent(*sparse, model, scan);
}

// 40 model points near the origin; the scan has 2 points there and a far cluster. The k nearest
// scan points of every model point are the same few, so small k has no perfect matching.
void crowded(std::vector<Vec3>& model, std::vector<Vec3>& scan) {
  model = testing::uniform_points(40, 8, 0.0, 5.0);
  scan = {Vec3(1, 1, 1), Vec3(2, 2, 2)};
  for (const auto& p : testing::uniform_points(60, 9, 0.0, 10.0))
    scan.push_back(p + Vec3(500, 0, 0));
}

TEST(PointMatching, InfeasibleGraphIsWidened) {
  std::vector<Vec3> model, scan;
  crowded(model, scan);
  const auto exact = match_points(model, scan, {.dense_limit = 1000});
  const auto m = match_points(
      model, scan, {.candidate_neighbors = 1, .dense_limit = 10, .max_widening_rounds = 10});
  ASSERT_TRUE(exact.ok() && m.ok());
  EXPECT_FALSE(m->used_dense);
  EXPECT_GE(m->widening_rounds, 5);  // k = 1, 2, ..., 32 still share too few scan points
  EXPECT_NEAR(m->total_cost, exact->total_cost, 1e-9 * exact->total_cost);
  expect_consistent(*m, model, scan);
}

TEST(PointMatching, InfeasibleGraphFallsBackToDense) {
  std::vector<Vec3> model, scan;
  crowded(model, scan);
  const auto exact = match_points(model, scan, {.dense_limit = 1000});
  const auto m = match_points(
      model, scan, {.candidate_neighbors = 1, .dense_limit = 10, .max_widening_rounds = 2});
  ASSERT_TRUE(exact.ok() && m.ok());
  EXPECT_TRUE(m->used_dense);
  EXPECT_EQ(m->widening_rounds, 2);
  EXPECT_NEAR(m->total_cost, exact->total_cost, 1e-9 * exact->total_cost);
  expect_consistent(*m, model, scan);
}

TEST(PointMatching, EmptyAndSingle) {
  auto m = match_points({}, {});
  ASSERT_TRUE(m.ok());
  EXPECT_TRUE(m->certified);
  EXPECT_TRUE(m->model_to_scan.empty());
  m = match_points({}, {Vec3(1, 2, 3)});
  ASSERT_TRUE(m.ok());
  EXPECT_TRUE(m->certified);
  m = match_points({Vec3(0, 0, 0)}, {});
  ASSERT_TRUE(m.ok());
  EXPECT_EQ(m->model_to_scan, std::vector<std::int32_t>{-1});
  m = match_points({Vec3(0, 0, 0)}, {Vec3(3, 0, 0), Vec3(1, 0, 0)});
  ASSERT_TRUE(m.ok());
  EXPECT_EQ(m->model_to_scan[0], 1);
  EXPECT_DOUBLE_EQ(m->total_cost, 1.0);
}

TEST(PointMatching, RejectsBadInput) {
  const auto nan =
      match_points({Vec3(0, std::numeric_limits<double>::quiet_NaN(), 0)}, {Vec3::Zero()});
  ASSERT_FALSE(nan.ok());
  EXPECT_NE(nan.message().find("model point 0"), std::string::npos);
  EXPECT_FALSE(match_points({Vec3::Zero()}, {Vec3::Zero()}, {.candidate_neighbors = 0}).ok());
}

TEST(PointMatching, CertificateRejectsSuboptimalAssignment) {
  const auto model = testing::uniform_points(30, 12);
  const auto scan = testing::uniform_points(30, 13);
  const auto m = match_points(model, scan);
  ASSERT_TRUE(m.ok());
  Assignment worse = m->assignment;
  std::swap(worse.row_to_col[0], worse.row_to_col[1]);
  worse.col_to_row[static_cast<std::size_t>(worse.row_to_col[0])] = 0;
  worse.col_to_row[static_cast<std::size_t>(worse.row_to_col[1])] = 1;
  EXPECT_FALSE(check_point_certificate(model, scan, worse, 1e-9).ok);
  EXPECT_TRUE(check_point_certificate(model, scan, m->assignment, 1e-7).ok);
}

}  // namespace
}  // namespace springscan::analysis
