#include "analysis/core/kdtree.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <nanoflann.hpp>
#include <numbers>
#include <random>
#include <thread>

#include "tests/analysis/synthetic.hpp"

namespace springscan::analysis {
namespace {

// Brute-force oracle (STYLE.md section 8): every point sorted by distance, ties by index.
std::vector<Neighbor> brute_force(const std::vector<Vec3>& points, const Vec3& q) {
  std::vector<Neighbor> all;
  for (std::uint32_t i = 0; i < points.size(); ++i)
    all.push_back({i, (points[i] - q).squaredNorm()});
  std::sort(all.begin(), all.end(), [](const Neighbor& a, const Neighbor& b) {
    return a.squared_distance < b.squared_distance ||
           (a.squared_distance == b.squared_distance && a.index < b.index);
  });
  return all;
}

TEST(KdTree, EmptyTreeAnswersNothing) {
  KdTree tree({});
  EXPECT_TRUE(tree.empty());
  EXPECT_FALSE(tree.nearest(Vec3::Zero()).has_value());
  std::vector<Neighbor> out{{1, 1.0}};
  tree.knn(Vec3::Zero(), 5, out);
  EXPECT_TRUE(out.empty());
  tree.radius(Vec3::Zero(), 10.0, out);
  EXPECT_TRUE(out.empty());
}

TEST(KdTree, SinglePoint) {
  KdTree tree({Vec3(1, 2, 3)});
  auto n = tree.nearest(Vec3(1, 2, 4));
  ASSERT_TRUE(n.has_value());
  EXPECT_EQ(n->index, 0u);
  EXPECT_DOUBLE_EQ(n->squared_distance, 1.0);
  EXPECT_FALSE(tree.nearest(Vec3(1, 2, 4), 0.5).has_value());
}

TEST(KdTree, NearestMatchesBruteForce) {
  const auto points = testing::uniform_points(5000, 1, -50.0, 50.0);
  KdTree tree(points);
  for (const auto& q : testing::uniform_points(300, 2, -50.0, 50.0)) {
    const auto expected = brute_force(points, q);
    auto n = tree.nearest(q);
    ASSERT_TRUE(n.has_value());
    EXPECT_DOUBLE_EQ(n->squared_distance, expected[0].squared_distance);
  }
}

TEST(KdTree, NearestWithinRespectsTheBound) {
  const auto points = testing::uniform_points(2000, 3, -50.0, 50.0);
  KdTree tree(points);
  for (const auto& q : testing::uniform_points(200, 4, -50.0, 50.0)) {
    const double d = std::sqrt(brute_force(points, q)[0].squared_distance);
    EXPECT_TRUE(tree.nearest(q, d * 1.001).has_value());
    EXPECT_FALSE(tree.nearest(q, d * 0.999).has_value());
  }
}

TEST(KdTree, KnnMatchesBruteForce) {
  const auto points = testing::uniform_points(3000, 5, -50.0, 50.0);
  KdTree tree(points);
  std::vector<Neighbor> got;
  for (const auto& q : testing::uniform_points(100, 6, -50.0, 50.0)) {
    const auto expected = brute_force(points, q);
    tree.knn(q, 12, got);
    ASSERT_EQ(got.size(), 12u);
    for (std::size_t i = 0; i < got.size(); ++i)
      EXPECT_DOUBLE_EQ(got[i].squared_distance, expected[i].squared_distance);
  }
  tree.knn(Vec3::Zero(), 5000, got);  // more than the tree holds
  EXPECT_EQ(got.size(), points.size());
}

TEST(KdTree, RadiusMatchesBruteForceAndIsInclusive) {
  const auto points = testing::uniform_points(3000, 7, -50.0, 50.0);
  KdTree tree(points);
  std::vector<Neighbor> got;
  for (const auto& q : testing::uniform_points(100, 8, -50.0, 50.0)) {
    const auto all = brute_force(points, q);
    // Just past the 21st point: sqrt then squaring may round below its exact distance.
    const double r = std::sqrt(all[20].squared_distance) * (1.0 + 1e-12);
    tree.radius(q, r, got);
    std::size_t expected = 0;
    while (expected < all.size() && all[expected].squared_distance <= r * r) ++expected;
    EXPECT_EQ(got.size(), expected);
    EXPECT_GE(got.size(), 21u);
  }
}

// Normals at random: about half the points face a query direction. The oracle walks the
// brute-force order for the first point facing that way.
TEST(KdTree, NearestAlongMatchesBruteForceWithAndWithoutRank) {
  const auto points = testing::uniform_points(4000, 21, -50.0, 50.0);
  std::vector<Vec3> normals = testing::uniform_points(points.size(), 22, -1.0, 1.0);
  KdTree tree(points);
  const auto queries = testing::uniform_points(300, 23, -50.0, 50.0);
  const auto directions = testing::uniform_points(queries.size(), 24, -1.0, 1.0);
  int rejected_by_rank = 0;
  for (std::size_t k = 0; k < queries.size(); ++k) {
    const Vec3& q = queries[k];
    const Vec3& dir = directions[k];
    const auto all = brute_force(points, q);
    std::size_t rank = 0;
    while (rank < all.size() && !(normals[all[rank].index].dot(dir) > 0.0)) ++rank;
    ASSERT_LT(rank, all.size());
    const auto any = tree.nearest_along(q, normals, dir);
    ASSERT_TRUE(any.has_value());
    EXPECT_DOUBLE_EQ(any->squared_distance, all[rank].squared_distance);
    // Within a bound: found only when the bound reaches it.
    const double d = std::sqrt(all[rank].squared_distance);
    EXPECT_TRUE(tree.nearest_along(q, normals, dir, d * 1.001).has_value());
    EXPECT_FALSE(tree.nearest_along(q, normals, dir, d * 0.999).has_value());
    // Among the 3 nearest of any normal, or nothing.
    const auto ranked = tree.nearest_along(q, normals, dir, 1e9, 3);
    EXPECT_EQ(ranked.has_value(), rank < 3) << "rank " << rank;
    if (ranked) {
      EXPECT_DOUBLE_EQ(ranked->squared_distance, all[rank].squared_distance);
    }
    if (rank >= 3) ++rejected_by_rank;
  }
  EXPECT_GT(rejected_by_rank, 0);  // the rank limit was exercised
  // A point facing nowhere near the direction, and normals of the wrong count: nothing.
  EXPECT_FALSE(tree.nearest_along(Vec3::Zero(), std::vector<Vec3>(3), Vec3::UnitZ()).has_value());
}

// With a floor on the dot product (unit vectors: the largest angle between the normals), the
// nearest point whose normal lies within 30 deg of the direction.
TEST(KdTree, NearestAlongWithinAnAngleMatchesBruteForce) {
  const auto points = testing::uniform_points(4000, 31, -50.0, 50.0);
  std::vector<Vec3> normals = testing::uniform_points(points.size(), 32, -1.0, 1.0);
  for (Vec3& n : normals) n.normalize();
  KdTree tree(points);
  const auto queries = testing::uniform_points(200, 33, -50.0, 50.0);
  const double min_dot = std::cos(30.0 * std::numbers::pi / 180.0);
  for (std::size_t k = 0; k < queries.size(); ++k) {
    const Vec3 dir = testing::uniform_points(1, 400 + unsigned(k), -1.0, 1.0)[0].normalized();
    const auto all = brute_force(points, queries[k]);
    std::size_t rank = 0;
    while (rank < all.size() && !(normals[all[rank].index].dot(dir) > min_dot)) ++rank;
    ASSERT_LT(rank, all.size());
    const auto found = tree.nearest_along(queries[k], normals, dir, 1e9, 0, min_dot);
    ASSERT_TRUE(found.has_value());
    EXPECT_EQ(found->index, all[rank].index);
    EXPECT_GT(normals[found->index].dot(dir), min_dot);
  }
}

TEST(KdTree, KnnAlongMatchesBruteForce) {
  const auto points = testing::uniform_points(3000, 25, -50.0, 50.0);
  const std::vector<Vec3> normals = testing::uniform_points(points.size(), 26, -1.0, 1.0);
  KdTree tree(points);
  const auto queries = testing::uniform_points(100, 27, -50.0, 50.0);
  const Vec3 dir = Vec3(0.3, -0.2, 0.9).normalized();
  std::uint32_t index[6];
  double d2[6];
  for (const auto& q : queries) {
    std::vector<double> expected;
    for (const Neighbor& n : brute_force(points, q))
      if (normals[n.index].dot(dir) > 0.0 && expected.size() < 6)
        expected.push_back(n.squared_distance);
    ASSERT_EQ(tree.knn_along(q, normals, dir, 6, index, d2), 6u);
    for (std::size_t i = 0; i < 6; ++i) {
      EXPECT_DOUBLE_EQ(d2[i], expected[i]);
      EXPECT_GT(normals[index[i]].dot(dir), 0.0);
    }
  }
}

TEST(KdTree, ConcurrentQueriesAgreeWithSerial) {
  const auto points = testing::uniform_points(20000, 9, -50.0, 50.0);
  const auto queries = testing::uniform_points(4000, 10, -50.0, 50.0);
  KdTree tree(points);
  std::vector<std::uint32_t> serial(queries.size()), parallel(queries.size());
  for (std::size_t i = 0; i < queries.size(); ++i) serial[i] = tree.nearest(queries[i])->index;
  std::vector<std::thread> threads;
  for (int t = 0; t < 4; ++t) {
    threads.emplace_back([&, t] {
      for (std::size_t i = static_cast<std::size_t>(t); i < queries.size(); i += 4)
        parallel[i] = tree.nearest(queries[i])->index;
    });
  }
  for (auto& thread : threads) thread.join();
  EXPECT_EQ(serial, parallel);
}

// KdTree searches its own copy of nanoflann's tree (kdtree.cpp, FlatTree) and must answer as
// nanoflann's own search does, to the index: among points at the same distance the one it visits
// first. A lattice with every point twice (ties everywhere), queried from lattice points and
// half steps, against a nanoflann index over the same points with the same leaf size.
struct LatticeAdaptor {
  const std::vector<Vec3>* points;
  std::size_t kdtree_get_point_count() const { return points->size(); }
  double kdtree_get_pt(std::size_t i, std::size_t dim) const { return (*points)[i][dim]; }
  template <class Box>
  bool kdtree_get_bbox(Box&) const {
    return false;
  }
};

TEST(KdTree, SameAnswersAsNanoflannTiesIncluded) {
  std::vector<Vec3> points;
  for (int x = 0; x < 12; ++x)
    for (int y = 0; y < 10; ++y)
      for (int z = 0; z < 6; ++z)
        for (int copy = 0; copy < 2; ++copy) points.emplace_back(x, 0.5 * y, 2.0 * z);
  std::mt19937 rng(37);
  std::shuffle(points.begin(), points.end(), rng);
  const KdTree tree(points);
  const LatticeAdaptor adaptor{&points};
  using Index = nanoflann::KDTreeSingleIndexAdaptor<
      nanoflann::L2_Simple_Adaptor<double, LatticeAdaptor, double, std::uint32_t>, LatticeAdaptor,
      3, std::uint32_t>;
  const Index index(3, adaptor, nanoflann::KDTreeSingleIndexAdaptorParams(16));
  std::uniform_int_distribution<int> step(-4, 28);
  std::vector<Neighbor> got;
  for (int n = 0; n < 600; ++n) {
    const double x = 0.5 * step(rng), y = 0.25 * step(rng), z = 0.5 * step(rng);
    const Vec3 q(x, y, z);
    constexpr std::size_t k = 9;
    std::uint32_t expected_index[k];
    double expected_d2[k];
    nanoflann::KNNResultSet<double, std::uint32_t, std::size_t> expected(k);
    expected.init(expected_index, expected_d2);
    index.findNeighbors(expected, q.data(), nanoflann::SearchParams());
    tree.knn(q, k, got);
    ASSERT_EQ(got.size(), k);
    for (std::size_t i = 0; i < k; ++i) {
      EXPECT_EQ(got[i].index, expected_index[i]) << "query " << q.transpose() << ", rank " << i;
      EXPECT_EQ(got[i].squared_distance, expected_d2[i]);
    }
    // The nearest is nanoflann's first: with k = 1 it keeps the first of equal distances too.
    nanoflann::KNNResultSet<double, std::uint32_t, std::size_t> first(1);
    first.init(expected_index, expected_d2);
    index.findNeighbors(first, q.data(), nanoflann::SearchParams());
    const auto nearest = tree.nearest(q);
    ASSERT_TRUE(nearest.has_value());
    EXPECT_EQ(nearest->index, expected_index[0]) << "query " << q.transpose();
    EXPECT_EQ(nearest->squared_distance, expected_d2[0]);
    // Within a radius, in nanoflann's order (its sort of the same points found in the same
    // order: equal distances included).
    const double r = 0.75 + 0.25 * static_cast<double>(n % 5);
    std::vector<std::pair<std::uint32_t, double>> in_radius;
    index.radiusSearch(q.data(), std::nextafter(r * r, 1e300), in_radius,
                       nanoflann::SearchParams(32, 0.0f, true));
    tree.radius(q, r, got);
    ASSERT_EQ(got.size(), in_radius.size());
    for (std::size_t i = 0; i < got.size(); ++i) {
      EXPECT_EQ(got[i].index, in_radius[i].first) << "query " << q.transpose() << ", " << i;
      EXPECT_EQ(got[i].squared_distance, in_radius[i].second);
    }
    // A bound above the nearest distance prunes the search but keeps its answer.
    const auto bounded = tree.nearest(q, std::sqrt(expected_d2[0]) + 0.3);
    ASSERT_TRUE(bounded.has_value());
    EXPECT_EQ(bounded->index, expected_index[0]);
  }
}

TEST(KdTree, SurvivesMove) {
  KdTree a(testing::uniform_points(100, 11, -50.0, 50.0));
  KdTree b = std::move(a);
  EXPECT_EQ(b.size(), 100u);
  EXPECT_TRUE(b.nearest(Vec3::Zero()).has_value());
}

}  // namespace
}  // namespace springscan::analysis
