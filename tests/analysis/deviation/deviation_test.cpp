#include "analysis/deviation/deviation.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "tests/analysis/synthetic.hpp"

namespace springscan::analysis {
namespace {

// An exact distance to the plane z = 0 with normal +z.
class PlaneDistance : public SurfaceDistance {
 public:
  SurfaceHit closest(const Vec3& q) const override {
    return {q.z(), Vec3(q.x(), q.y(), 0.0), Vec3::UnitZ(), 0};
  }
};

PartModel plane_model() {
  PartModel model;
  for (int x = 0; x <= 100; ++x)
    for (int y = 0; y <= 50; ++y) {
      model.samples.points.emplace_back(x, y, 0.0);
      model.samples.normals.push_back(Vec3::UnitZ());
    }
  return model;
}

TEST(Deviation, SignedByTheSampleNormalWithStatistics) {
  const PartModel model = plane_model();
  const KdTree tree(model.samples.points);
  // 100 points: 0.01 .. 1.00 mm above, except every 10th below.
  std::vector<Vec3> scan;
  for (int i = 1; i <= 100; ++i)
    scan.emplace_back(10.3 + i * 0.5, 20.7, (i % 10 ? 1 : -1) * 0.01 * i);
  auto r = signed_deviation(scan, model, tree);
  ASSERT_TRUE(r) << r.message();
  EXPECT_FALSE(r->exact);
  for (int i = 1; i <= 100; ++i)
    EXPECT_NEAR(r->signed_distance_mm[static_cast<std::size_t>(i - 1)],
                (i % 10 ? 1 : -1) * 0.01 * i, 1e-12);
  const auto& s = r->statistics;
  EXPECT_NEAR(s.max_mm, 0.99, 1e-12);
  EXPECT_NEAR(s.min_mm, -1.0, 1e-12);
  EXPECT_NEAR(s.p95_mm, 0.95, 1e-12);  // nearest rank of |d| = 0.01 .. 1.00
  EXPECT_EQ(s.points, 100u);
}

TEST(Deviation, UsesTheExactSurfaceWhenTheModelHasOne) {
  PartModel model = plane_model();
  model.distance = std::make_shared<PlaneDistance>();
  const KdTree tree(model.samples.points);
  auto r = signed_deviation({Vec3(0.5, 0.5, 0.25), Vec3(500, 500, -2)}, model, tree);
  ASSERT_TRUE(r);
  EXPECT_TRUE(r->exact);
  EXPECT_DOUBLE_EQ(r->signed_distance_mm[0], 0.25);
  EXPECT_DOUBLE_EQ(r->signed_distance_mm[1], -2.0);
}

TEST(Deviation, ThreadCountDoesNotChangeTheResult) {
  const PointCloud part = testing::bumpy_surface(20000, 43);
  PartModel model;
  model.samples = part;
  const KdTree tree(part.points);
  PointCloud scan = testing::bumpy_surface(30000, 44);
  testing::add_noise(scan.points, 0.1, 45);
  auto one = signed_deviation(scan.points, model, tree, {0.2, 0.0, 1});
  auto three = signed_deviation(scan.points, model, tree, {0.2, 0.0, 3});
  ASSERT_TRUE(one && three);
  EXPECT_EQ(one->signed_distance_mm, three->signed_distance_mm);
  EXPECT_EQ(one->statistics.mean_mm, three->statistics.mean_mm);
  EXPECT_NEAR(one->statistics.rms_mm, 0.1, 0.02);  // the noise along the normal
}

TEST(Deviation, ColourMapEndsAndMiddle) {
  EXPECT_EQ(deviation_color(0.0, 1.0), (Rgb{0, 255, 0}));
  EXPECT_EQ(deviation_color(1.0, 1.0), (Rgb{255, 0, 0}));
  EXPECT_EQ(deviation_color(-5.0, 1.0), (Rgb{0, 0, 255}));
  EXPECT_EQ(deviation_color(0.5, 1.0), (Rgb{128, 128, 0}));
}

TEST(Deviation, BadInputs) {
  PartModel model = plane_model();
  const KdTree tree(model.samples.points);
  EXPECT_FALSE(signed_deviation({Vec3(NAN, 0, 0)}, model, tree));
  // No tolerance here to get wrong: the stage measures, the verdict judges (verdict_test.cpp).
  PartModel no_normals = model;
  no_normals.samples.normals.clear();
  EXPECT_FALSE(signed_deviation({Vec3(0, 0, 0)}, no_normals, tree));
  auto empty = signed_deviation({}, model, tree);
  ASSERT_TRUE(empty);
  EXPECT_EQ(empty->statistics.points, 0u);
}

// The p95 is selected by a histogram of the values' leading bits (deviation.cpp): it must be the
// nearest-rank value of a full sort, whatever the spread (many octaves, ties, zeros of either
// sign, infinities) and with a NaN among them (then the plain selection).
TEST(Deviation, P95IsTheNearestRankOfTheSortedMagnitudes) {
  std::mt19937_64 rng(37);
  std::normal_distribution<double> noise(0.0, 0.05);
  std::uniform_int_distribution<int> octave(-30, 6);
  for (const std::size_t n :
       {std::size_t{1}, std::size_t{7}, std::size_t{1000}, std::size_t{200'003}}) {
    std::vector<double> d(n);
    for (std::size_t i = 0; i < n; ++i) {
      switch (i % 5) {
        case 0:
          d[i] = noise(rng);
          break;
        case 1:
          d[i] = std::ldexp(noise(rng), octave(rng));
          break;
        case 2:
          d[i] = 0.25;
          break;  // ties
        case 3:
          d[i] = (i % 2 ? -0.0 : 0.0);
          break;
        default:
          d[i] = -std::abs(noise(rng)) * 20.0;
      }
    }
    if (n > 100) d[n / 2] = std::numeric_limits<double>::infinity();
    std::vector<double> sorted(n);
    for (std::size_t i = 0; i < n; ++i) sorted[i] = std::abs(d[i]);
    std::sort(sorted.begin(), sorted.end());
    const auto rank = static_cast<std::size_t>(std::ceil(0.95 * static_cast<double>(n))) - 1;
    EXPECT_EQ(deviation_statistics(d).p95_mm, sorted[rank]) << n << " values";
  }
  const std::vector<double> with_nan = {0.3, std::nan(""), -0.1, 0.2};
  const double p95 = deviation_statistics(with_nan).p95_mm;  // the plain selection: one of them
  EXPECT_TRUE(std::isnan(p95) || p95 == 0.3 || p95 == 0.1 || p95 == 0.2) << p95;
}

}  // namespace
}  // namespace springscan::analysis
