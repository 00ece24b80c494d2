#include "analysis/core/spatial_order.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>
#include <tuple>

namespace springscan::analysis {
namespace {

// Oracle: the Morton code of each point's cell, one bit at a time.
std::vector<std::uint64_t> morton_keys(const std::vector<Vec3>& points) {
  Vec3 lo = points[0], hi = points[0];
  for (const Vec3& p : points) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  const double cells = double(1 << kSpatialOrderBits);
  const double extent = (hi - lo).maxCoeff();
  std::vector<std::uint64_t> key(points.size(), 0);
  for (std::size_t i = 0; i < points.size(); ++i)
    for (int axis = 0; axis < 3; ++axis) {
      const double t = extent > 0.0 ? (points[i][axis] - lo[axis]) / extent * cells : 0.0;
      const auto cell = static_cast<std::uint64_t>(std::min(t, cells - 1.0));
      for (int bit = 0; bit < kSpatialOrderBits; ++bit)
        key[i] |= ((cell >> bit) & 1u) << (3 * bit + axis);
    }
  return key;
}

// Oracle: a stable sort by the Morton code of each point's cell.
std::vector<std::uint32_t> by_sorting(const std::vector<Vec3>& points) {
  const std::vector<std::uint64_t> key = morton_keys(points);
  std::vector<std::uint32_t> order(points.size());
  std::iota(order.begin(), order.end(), 0u);
  std::stable_sort(order.begin(), order.end(),
                   [&](std::uint32_t a, std::uint32_t b) { return key[a] < key[b]; });
  return order;
}

// A bent sheet (two planes at 90 degrees, 200 x 100 mm each) sampled at random, in random order.
std::vector<Vec3> shuffled_sheet(std::size_t n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<Vec3> points;
  for (std::size_t i = 0; i < n; ++i) {
    const double s = 200.0 * u(rng), w = 100.0 * u(rng);
    points.push_back(s < 100.0 ? Vec3(s, w, 0.0) : Vec3(100.0, w, s - 100.0));
  }
  return points;
}

double mean_step(const std::vector<Vec3>& points, const std::vector<std::uint32_t>& order) {
  double sum = 0.0;
  for (std::size_t k = 1; k < order.size(); ++k)
    sum += (points[order[k]] - points[order[k - 1]]).norm();
  return sum / static_cast<double>(order.size() - 1);
}

TEST(SpatialOrder, EmptyAndTinyInputs) {
  EXPECT_TRUE(spatial_order({}).empty());
  EXPECT_EQ(spatial_order({Vec3(1, 2, 3)}), std::vector<std::uint32_t>{0});
  // All points in one cell keep their input order.
  EXPECT_EQ(spatial_order(std::vector<Vec3>(5, Vec3(4, 4, 4))),
            (std::vector<std::uint32_t>{0, 1, 2, 3, 4}));
  EXPECT_EQ(spatial_order({Vec3(10, 0, 0), Vec3(0, 0, 0)}), (std::vector<std::uint32_t>{1, 0}));
}

TEST(SpatialOrder, MatchesAStableSortByMortonCode) {
  // Enough points for several parallel blocks, and repeated cells (rounded coordinates).
  std::vector<Vec3> points = shuffled_sheet(30'000, 1);
  for (std::size_t i = 0; i < points.size(); i += 3) points[i] = points[i].array().round();
  EXPECT_EQ(spatial_order(points, 1), by_sorting(points));
  EXPECT_EQ(spatial_order(points, 2), by_sorting(points));
}

TEST(SpatialOrder, NeighboursInTheOrderAreNeighboursInSpace) {
  const std::vector<Vec3> points = shuffled_sheet(50'000, 2);
  std::vector<std::uint32_t> identity(points.size());
  std::iota(identity.begin(), identity.end(), 0u);
  const std::vector<std::uint32_t> order = spatial_order(points);
  std::vector<std::uint32_t> sorted = order;
  std::sort(sorted.begin(), sorted.end());
  ASSERT_EQ(sorted, identity);  // a permutation
  // Random order: a step of about a third of the part (~90 mm); this order: about the point
  // spacing (0.6 mm) with the Z-curve's occasional jumps.
  EXPECT_GT(mean_step(points, identity), 50.0);
  EXPECT_LT(mean_step(points, order), 2.0);
}

TEST(SpatialOrder, CoherenceOfScanLinesAndOfAShuffle) {
  std::vector<Vec3> points = shuffled_sheet(50'000, 3);
  EXPECT_FALSE(spatially_coherent(points));
  std::vector<std::uint32_t> identity(points.size());
  std::iota(identity.begin(), identity.end(), 0u);
  EXPECT_EQ(search_order(points), spatial_order(points));
  std::vector<Vec3> ordered;
  for (const std::uint32_t i : spatial_order(points)) ordered.push_back(points[i]);
  EXPECT_TRUE(spatially_coherent(ordered));
  // Scanner lines: 0.5 mm apart along y, each along the profile.
  std::sort(points.begin(), points.end(), [](const Vec3& a, const Vec3& b) {
    const int la = static_cast<int>(a.y() / 0.5), lb = static_cast<int>(b.y() / 0.5);
    return la != lb ? la < lb : a.x() + a.z() < b.x() + b.z();
  });
  EXPECT_TRUE(spatially_coherent(points));
  EXPECT_EQ(search_order(points), identity);
  EXPECT_TRUE(spatially_coherent({}));
  EXPECT_TRUE(spatially_coherent({Vec3(1, 2, 3)}));
}

// The analysis takes its scan in canonical_order (issue 37): the same point set in any order
// gives the same sequence of points, on any thread count, and it is a Morton order.
TEST(SpatialOrder, CanonicalOrderDependsOnThePointsAlone) {
  // Several parallel blocks, and repeated cells (every third point rounded to the millimetre).
  std::vector<Vec3> points = shuffled_sheet(30'000, 4);
  for (std::size_t i = 0; i < points.size(); i += 3) points[i] = points[i].array().round();
  const auto in_order = [](const std::vector<Vec3>& from, const std::vector<std::uint32_t>& o) {
    std::vector<Vec3> out;
    for (const std::uint32_t i : o) out.push_back(from[i]);
    return out;
  };
  const std::vector<Vec3> canonical = in_order(points, canonical_order(points, 1));
  std::vector<Vec3> other = points;
  std::reverse(other.begin(), other.end());
  std::mt19937 rng(5);
  EXPECT_EQ(in_order(other, canonical_order(other, 2)), canonical);
  std::shuffle(other.begin(), other.end(), rng);
  EXPECT_EQ(in_order(other, canonical_order(other, 1)), canonical);
  EXPECT_EQ(in_order(other, canonical_order(other, 2)), canonical);
  // The cells in Morton order (the oracle's stable sort), points within a cell by coordinates.
  const std::vector<Vec3> by_cell = in_order(points, by_sorting(points));
  ASSERT_EQ(by_cell.size(), canonical.size());
  std::vector<Vec3> cells_of_canonical = canonical, cells_of_oracle = by_cell;
  const auto lexicographic = [](const Vec3& a, const Vec3& b) {
    return std::tie(a.x(), a.y(), a.z()) < std::tie(b.x(), b.y(), b.z());
  };
  std::sort(cells_of_canonical.begin(), cells_of_canonical.end(), lexicographic);
  std::sort(cells_of_oracle.begin(), cells_of_oracle.end(), lexicographic);
  EXPECT_EQ(cells_of_canonical, cells_of_oracle);  // the same points
  EXPECT_EQ(spatial_order(canonical, 1), by_sorting(canonical));
  std::vector<std::uint32_t> identity(canonical.size());
  std::iota(identity.begin(), identity.end(), 0u);
  // Already canonical: a stable sort by cell leaves it as it is.
  EXPECT_EQ(by_sorting(canonical), identity);
  EXPECT_TRUE(canonical_order({}).empty());
}

// canonical_order against a comparison sort by (cell, x, y, z, input index), with points whose x
// differ in the last bit only, equal x, and repeated points (CanonicalOrderDependsOnThePointsAlone
// checks only that the order does not depend on the input's; this, what the order is).
TEST(SpatialOrder, CanonicalOrderIsTheSortByCellThenCoordinates) {
  std::vector<Vec3> points = shuffled_sheet(20'000, 9);
  for (std::size_t i = 0; i < points.size(); i += 5) points[i] = points[i].array().round();
  for (std::size_t i = 1; i + 1 < points.size(); i += 7) {
    points[i + 1] = points[i];
    points[i + 1].x() = std::nextafter(points[i].x(), 1e9);    // one ulp apart
    if (i % 3 == 1) points[i + 1].y() = points[i].y() + 1e-3;  // equal x, y apart
  }
  const std::vector<std::uint64_t> key = morton_keys(points);
  std::vector<std::uint32_t> truth(points.size());
  std::iota(truth.begin(), truth.end(), 0u);
  std::sort(truth.begin(), truth.end(), [&](std::uint32_t a, std::uint32_t b) {
    const Vec3 &p = points[a], &q = points[b];
    return std::tie(key[a], p.x(), p.y(), p.z(), a) < std::tie(key[b], q.x(), q.y(), q.z(), b);
  });
  EXPECT_EQ(canonical_order(points, 1), truth);
  const OrderedPoints ordered = canonically_ordered(points, 2);
  EXPECT_EQ(ordered.order, truth);
  ASSERT_EQ(ordered.points.size(), truth.size());
  for (std::size_t k = 0; k < truth.size(); ++k)
    ASSERT_EQ(ordered.points[k], points[truth[k]]) << k;
  EXPECT_TRUE(canonically_ordered({}).points.empty());
}

}  // namespace
}  // namespace springscan::analysis
