// TriangleBvh (analysis/core/triangle_bvh.hpp) against brute force.
#include "analysis/core/triangle_bvh.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <set>

#include "tests/analysis/synthetic.hpp"

namespace springscan::analysis {
namespace {

// Two slivers sharing an edge, the query inside the second: its distance is a rounding error
// whose square root squared is below it (the case that once lost the nearest triangle).
TEST(TriangleBvh, NearestFindsTheTriangleThatContainsTheQuery) {
  const std::vector<Vec3> v = {Vec3(21, 1, 0), Vec3(22, 1, 0), Vec3(30, 24, 0), Vec3(20, 1, 0)};
  const TriangleBvh bvh(v, {{3, 0, 2}, {0, 1, 2}}, {.leaf_size = 1});
  const auto foot = bvh.nearest(Vec3(23, 4, 0));
  ASSERT_TRUE(foot);
  EXPECT_EQ(foot->triangle, 1u);
  EXPECT_LT(foot->squared_distance, 1e-20);
}

// `count` small triangles at random: centres within +-10 mm scaled by `extent` per axis,
// corners within +-10 mm scaled by `size` of their centre.
struct Soup {
  std::vector<Vec3> v;
  std::vector<std::array<std::uint32_t, 3>> t;
};
Soup random_triangles(std::mt19937& rng, std::uint32_t count, const Vec3& extent,
                      const Vec3& size) {
  std::uniform_real_distribution<double> u(-10.0, 10.0);
  const auto draw = [&] { return testing::draw_vec3(u, rng); };
  Soup s;
  for (std::uint32_t i = 0; i < count; ++i) {
    const Vec3 a = draw().cwiseProduct(extent);
    for (int k = 0; k < 3; ++k) s.v.push_back(a + draw().cwiseProduct(size));
    s.t.push_back({3 * i, 3 * i + 1, 3 * i + 2});
  }
  return s;
}

TEST(TriangleBvh, NearestMatchesBruteForceOnRandomTriangles) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-10.0, 10.0);
  const Soup soup = random_triangles(rng, 300, Vec3::Ones(), Vec3::Constant(0.2));
  const auto& v = soup.v;
  const auto& t = soup.t;
  const TriangleBvh bvh(v, t);
  EXPECT_FALSE(TriangleBvh().nearest(Vec3::Zero()));
  for (int q = 0; q < 500; ++q) {
    const Vec3 p(u(rng), u(rng), u(rng));
    double best = 1e300;
    for (const auto& tri : t)
      best =
          std::min(best, closest_on_triangle(p, v[tri[0]], v[tri[1]], v[tri[2]]).squared_distance);
    EXPECT_DOUBLE_EQ(bvh.nearest(p)->squared_distance, best);
  }
}

// near_from, whatever leaf it starts in, finds what near finds: the same nearest distance and
// every triangle within the slack of it (a search may also report farther ones it met first).
TEST(TriangleBvh, NearFromAnyStartFindsWhatNearFinds) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-10.0, 10.0);
  // Flat-ish triangles in a slab, as a tessellated sheet offers them.
  const Soup soup = random_triangles(rng, 400, Vec3(1, 1, 0.3), Vec3(0.4, 0.4, 0.04));
  const TriangleBvh bvh(soup.v, soup.t);
  constexpr double kSlack = 0.3;
  const auto within = [&](double nearest, auto&& search) {
    std::set<std::uint32_t> found;
    search([&](const TriangleFoot& f) {
      if (std::sqrt(f.squared_distance) <= nearest + kSlack) found.insert(f.triangle);
    });
    return found;
  };
  std::uint32_t previous_slot = 0;
  for (int q = 0; q < 400; ++q) {
    const Vec3 p = testing::draw_vec3(u, rng);
    const double nearest = bvh.near(p, kSlack, [](const TriangleFoot&) {});
    // Starts: the previous query's nearest triangle (as CadDistance chains them), an arbitrary
    // slot, and one out of range.
    for (const std::uint32_t start : {previous_slot, static_cast<std::uint32_t>(q) % 400u, ~0u}) {
      const double from = bvh.near_from(start, p, kSlack, [](const TriangleFoot&) {});
      EXPECT_DOUBLE_EQ(from, nearest);
      const auto plain = within(nearest, [&](auto&& f) { bvh.near(p, kSlack, f); });
      const auto started = within(nearest, [&](auto&& f) { bvh.near_from(start, p, kSlack, f); });
      EXPECT_EQ(started, plain) << "query " << q << " from slot " << start;
    }
    bvh.near(p, 0.0, [&](const TriangleFoot& f) {
      if (std::sqrt(f.squared_distance) <= nearest) previous_slot = f.slot;
    });
  }
}

// Every triangle within the slack of the nearest is reported, as brute force finds them: the
// triangles' own boxes, tested before their closest points, drop none of them (slack 0, the
// nearest alone, included).
TEST(TriangleBvh, NearReportsEveryTriangleWithinTheSlack) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-10.0, 10.0);
  const Soup soup = random_triangles(rng, 400, Vec3(1, 1, 0.3), Vec3(0.4, 0.4, 0.04));
  const TriangleBvh bvh(soup.v, soup.t, {.leaf_size = 8});
  for (const double slack : {0.0, 0.05, 0.5}) {
    for (int q = 0; q < 300; ++q) {
      const Vec3 p = testing::draw_vec3(u, rng);
      std::vector<double> d(soup.t.size());
      double nearest = 1e300;
      for (std::size_t i = 0; i < soup.t.size(); ++i) {
        const auto& tri = soup.t[i];
        d[i] = std::sqrt(closest_on_triangle(p, soup.v[tri[0]], soup.v[tri[1]], soup.v[tri[2]])
                             .squared_distance);
        nearest = std::min(nearest, d[i]);
      }
      std::set<std::uint32_t> expected, found;
      for (std::uint32_t i = 0; i < d.size(); ++i)
        if (d[i] <= nearest + slack) expected.insert(i);
      const double got = bvh.near(p, slack, [&](const TriangleFoot& f) {
        if (std::sqrt(f.squared_distance) <= nearest + slack) found.insert(f.triangle);
      });
      EXPECT_EQ(got, nearest);
      EXPECT_EQ(found, expected) << "query " << q << ", slack " << slack;
    }
  }
}

}  // namespace
}  // namespace springscan::analysis
