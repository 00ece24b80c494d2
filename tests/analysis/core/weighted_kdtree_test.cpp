// WeightedKdTree (kdtree.hpp): additively weighted nearest neighbour against brute force.
#include <gtest/gtest.h>

#include <limits>
#include <random>
#include <stdexcept>

#include "analysis/core/kdtree.hpp"

namespace springscan::analysis {
namespace {

TEST(WeightedKdTree, MatchesBruteForce) {
  std::mt19937 rng(4);
  std::uniform_real_distribution<double> u(0.0, 50.0), w(0.0, 400.0);
  std::vector<Vec3> points(500);
  std::vector<double> weights(500);
  for (std::size_t i = 0; i < points.size(); ++i) {
    points[i] = Vec3(u(rng), u(rng), u(rng));
    weights[i] = i % 3 == 0 ? 0.0 : w(rng);
  }
  const WeightedKdTree tree(points, weights);
  std::vector<Neighbor> below;
  for (int q = 0; q < 200; ++q) {
    const Vec3 query(u(rng), u(rng), u(rng));
    double best = std::numeric_limits<double>::infinity();
    std::size_t count = 0;
    const double bound = 150.0;
    for (std::size_t j = 0; j < points.size(); ++j) {
      const double value = (query - points[j]).squaredNorm() + weights[j];
      best = std::min(best, value);
      if (value < bound) ++count;
    }
    const auto nearest = tree.nearest(query);
    ASSERT_TRUE(nearest.has_value());
    EXPECT_NEAR(nearest->squared_distance, best, 1e-9);
    tree.below(query, bound, below);
    EXPECT_EQ(below.size(), count);
    for (const auto& nb : below) EXPECT_LT(nb.squared_distance, bound);
  }
}

TEST(WeightedKdTree, EmptyAndInvalid) {
  const WeightedKdTree empty({}, {});
  EXPECT_FALSE(empty.nearest(Vec3::Zero()).has_value());
  EXPECT_THROW(WeightedKdTree({Vec3::Zero()}, {-1.0}), std::invalid_argument);
  EXPECT_THROW(WeightedKdTree({Vec3::Zero()}, {}), std::invalid_argument);
}

}  // namespace
}  // namespace springscan::analysis
