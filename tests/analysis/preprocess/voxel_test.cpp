#include "analysis/preprocess/voxel.hpp"

#include <gtest/gtest.h>

#include "tests/analysis/synthetic.hpp"

namespace springscan::analysis {
namespace {

TEST(Voxel, CentroidsPerOccupiedVoxelInFirstSeenOrder) {
  PointCloud cloud;
  cloud.points = {Vec3(0.1, 0.1, 0.1), Vec3(5.5, 0.2, 0.2), Vec3(0.3, 0.5, 0.9),
                  Vec3(5.7, 0.4, 0.6)};
  cloud.normals = {Vec3::UnitZ(), Vec3::UnitX(), Vec3::UnitZ(), Vec3::UnitX()};
  auto r = voxel_reduce(cloud, {1.0});
  ASSERT_TRUE(r) << r.message();
  ASSERT_EQ(r->cloud.size(), 2u);
  EXPECT_TRUE(r->cloud.points[0].isApprox(Vec3(0.2, 0.3, 0.5)));
  EXPECT_TRUE(r->cloud.points[1].isApprox(Vec3(5.6, 0.3, 0.4)));
  EXPECT_EQ(r->counts, (std::vector<std::uint32_t>{2, 2}));
  EXPECT_TRUE(r->cloud.normals[1].isApprox(Vec3::UnitX()));
}

TEST(Voxel, OnePointPerVoxelAndDeterministic) {
  const PointCloud part = testing::bumpy_surface(30000, 11);
  auto a = voxel_reduce(part, {2.0});
  auto b = voxel_reduce(part, {2.0});
  ASSERT_TRUE(a && b);
  EXPECT_EQ(a->cloud.points, b->cloud.points);
  EXPECT_LT(a->cloud.size(), part.size() / 5);
  std::uint64_t total = 0;
  for (auto c : a->counts) total += c;
  EXPECT_EQ(total, part.size());
  // Each centroid stays within its voxel's diagonal of the surface points.
  EXPECT_LT(a->cloud.size(), 120u * 70u / 4u * 2u);
}

TEST(Voxel, BadInputs) {
  PointCloud empty;
  auto e = voxel_reduce(empty, {1.0});
  ASSERT_TRUE(e);
  EXPECT_TRUE(e->cloud.empty());
  PointCloud one;
  one.points = {Vec3(1, 2, 3)};
  EXPECT_FALSE(voxel_reduce(one, {0.0}));
  EXPECT_FALSE(voxel_reduce(one, {-1.0}));
  one.points.push_back(Vec3(1e9, 0, 0));
  EXPECT_FALSE(voxel_reduce(one, {1e-3}));  // key overflow is refused, not wrapped
  one.points.push_back(Vec3(NAN, 0, 0));
  EXPECT_FALSE(voxel_reduce(one, {1.0}));
}

}  // namespace
}  // namespace springscan::analysis
