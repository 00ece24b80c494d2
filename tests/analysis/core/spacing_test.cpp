// median_neighbour_spacing against samplings whose spacing the test sets.
#include "analysis/core/spacing.hpp"

#include <gtest/gtest.h>

#include <vector>

namespace springscan::analysis {
namespace {

TEST(Spacing, GridGivesItsPitch) {
  std::vector<Vec3> grid;
  for (int i = 0; i < 20; ++i)
    for (int j = 0; j < 10; ++j) grid.emplace_back(2.5 * i, 2.5 * j, 0.0);
  const KdTree tree(grid);
  EXPECT_DOUBLE_EQ(median_neighbour_spacing(tree, grid), 2.5);
  // A sample of the points as probes: the same pitch.
  const std::vector<Vec3> probes(grid.begin(), grid.begin() + 15);
  EXPECT_DOUBLE_EQ(median_neighbour_spacing(tree, probes), 2.5);
}

TEST(Spacing, NoNeighbourGivesZero) {
  const std::vector<Vec3> one = {Vec3(1.0, 2.0, 3.0)};
  EXPECT_EQ(median_neighbour_spacing(KdTree(one), one), 0.0);
  EXPECT_EQ(median_neighbour_spacing(KdTree(one), {}), 0.0);
}

}  // namespace
}  // namespace springscan::analysis
