#include "analysis/preprocess/voxel.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>

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

// The reference: floor keys, a map from key to first-seen slot, sums in point order. The
// parallel keys and the repeated-voxel shortcut must give the same centroids to the last bit, in
// a shuffled order and in a sorted one (where consecutive points share voxels).
TEST(Voxel, SameBitsAsASerialFloorPass) {
  PointCloud part = testing::bumpy_surface(60000, 5);
  const auto reference = [](const PointCloud& c, double size) {
    Vec3 lo = c.points[0];
    for (const Vec3& p : c.points) lo = lo.cwiseMin(p);
    const double inv = 1.0 / size;
    std::map<std::array<long, 3>, std::size_t> slot;
    std::vector<Vec3> sums, normal_sums;
    std::vector<std::uint32_t> counts;
    for (std::size_t i = 0; i < c.size(); ++i) {
      const Vec3 cell = ((c.points[i] - lo) * inv).array().floor();
      const std::array<long, 3> key{long(cell.x()), long(cell.y()), long(cell.z())};
      auto [it, fresh] = slot.emplace(key, sums.size());
      if (fresh) {
        sums.push_back(Vec3::Zero());
        normal_sums.push_back(Vec3::Zero());
        counts.push_back(0);
      }
      sums[it->second] += c.points[i];
      normal_sums[it->second] += c.normals[i];
      ++counts[it->second];
    }
    PointCloud out;
    for (std::size_t k = 0; k < sums.size(); ++k) {
      out.points.push_back(sums[k] / double(counts[k]));
      out.normals.push_back(normal_sums[k].normalized());
    }
    return std::make_pair(out, counts);
  };
  for (const bool sorted : {false, true}) {
    if (sorted) {  // points and normals together, by x
      std::vector<std::size_t> by_x(part.size());
      for (std::size_t i = 0; i < by_x.size(); ++i) by_x[i] = i;
      std::sort(by_x.begin(), by_x.end(), [&](std::size_t a, std::size_t b) {
        return part.points[a].x() < part.points[b].x();
      });
      PointCloud s;
      for (const std::size_t i : by_x) {
        s.points.push_back(part.points[i]);
        s.normals.push_back(part.normals[i]);
      }
      part = std::move(s);
    }
    const double size = 1.5;  // 1/1.5 is inexact: the keys' products round as the reference's
    const auto got = voxel_reduce(part, {size});
    ASSERT_TRUE(got) << got.message();
    const auto [want, counts] = reference(part, size);
    EXPECT_EQ(got->counts, counts);
    EXPECT_EQ(got->cloud.points, want.points);
    EXPECT_EQ(got->cloud.normals, want.normals);
  }
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
