#include "analysis/preprocess/kcenter.hpp"

#include <gtest/gtest.h>

#include <iostream>

#include "tests/analysis/synthetic.hpp"

namespace springscan::analysis {
namespace {

double covering_radius(const std::vector<Vec3>& points, const std::vector<std::uint32_t>& c) {
  double worst = 0.0;
  for (const auto& p : points) {
    double best = 1e300;
    for (auto i : c) best = std::min(best, (p - points[i]).norm());
    worst = std::max(worst, best);
  }
  return worst;
}

TEST(KCenter, FastSelectsExactlyTheNaiveCentersBothVariants) {
  const PointCloud part = testing::bumpy_surface(20000, 5);
  for (const KCenterSettings& s : {KCenterSettings{300, 0.0, 7, 64}, KCenterSettings{0, 4.0, 0, 32},
                                   KCenterSettings{1000, 0.0, 19999, 128}}) {
    auto fast = kcenter_reduce(part.points, s);
    auto naive = kcenter_reduce_naive(part.points, s);
    ASSERT_TRUE(fast && naive);
    EXPECT_EQ(fast->centers, naive->centers);
    EXPECT_EQ(fast->covering_radius_mm, naive->covering_radius_mm);
    EXPECT_EQ(fast->centers.front(), s.start_index);
  }
}

TEST(KCenter, TiesGoToTheLowestIndexInBothVersions) {
  // A regular grid has many equal distances: the tie rule decides every step.
  std::vector<Vec3> grid;
  for (int x = 0; x < 30; ++x)
    for (int y = 0; y < 30; ++y) grid.emplace_back(x, y, 0);
  KCenterSettings s{50, 0.0, 0, 16};
  auto fast = kcenter_reduce(grid, s), naive = kcenter_reduce_naive(grid, s);
  ASSERT_TRUE(fast && naive);
  EXPECT_EQ(fast->centers, naive->centers);
  EXPECT_EQ(naive->centers[1], 29u * 30u + 29u);  // the far corner is unique
}

TEST(KCenter, RadiusVariantCoversWithinW) {
  const PointCloud part = testing::bumpy_surface(5000, 6);
  KCenterSettings s;
  s.radius_mm = 10.0;
  auto r = kcenter_reduce(part.points, s);
  ASSERT_TRUE(r);
  EXPECT_LT(r->covering_radius_mm, 10.0);
  EXPECT_NEAR(r->covering_radius_mm, covering_radius(part.points, r->centers), 1e-9);
  // Greedy centers are pairwise at least w apart (each was >= w from all earlier ones).
  for (std::size_t i = 0; i < r->centers.size(); ++i)
    for (std::size_t j = 0; j < i; ++j)
      EXPECT_GE((part.points[r->centers[i]] - part.points[r->centers[j]]).norm(), 10.0);
}

TEST(KCenter, CountVariantIsATwoApproximationOnAKnownInstance) {
  // Four tight clusters 100 mm apart: the optimum for k = 4 is below 1 mm; greedy must find
  // one center per cluster, so its radius is at most twice the optimum's.
  std::vector<Vec3> points;
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-0.5, 0.5);
  for (int c = 0; c < 4; ++c)
    for (int i = 0; i < 100; ++i)
      points.push_back(Vec3(100.0 * c, 37.0 * (c % 2), 0) + testing::draw_vec3(u, rng));
  auto r = kcenter_reduce(points, {4, 0.0, 0, 16});
  ASSERT_TRUE(r);
  EXPECT_EQ(r->centers.size(), 4u);
  EXPECT_LT(r->covering_radius_mm, 2.0 * std::sqrt(3.0) * 0.5 * 2.0);
}

TEST(KCenter, EmptyTinyDuplicateAndBadInputs) {
  auto empty = kcenter_reduce({});
  ASSERT_TRUE(empty);
  EXPECT_TRUE(empty->centers.empty());
  auto two = kcenter_reduce({Vec3(0, 0, 0), Vec3(3, 4, 0)}, {5, 0.0, 0, 16});
  ASSERT_TRUE(two);
  EXPECT_EQ(two->centers, (std::vector<std::uint32_t>{0, 1}));
  EXPECT_EQ(two->covering_radius_mm, 0.0);
  auto same = kcenter_reduce(std::vector<Vec3>(10, Vec3(1, 2, 3)), {5, 0.0, 0, 16});
  ASSERT_TRUE(same);
  EXPECT_EQ(same->centers.size(), 1u);  // no distinct point left to add
  EXPECT_FALSE(kcenter_reduce({Vec3(0, 0, 0), Vec3(NAN, 0, 0)}));
  EXPECT_FALSE(kcenter_reduce({Vec3(0, 0, 0)}, {0, 0.0, 0, 16}));
  EXPECT_FALSE(kcenter_reduce({Vec3(0, 0, 0)}, {1, 0.0, 5, 16}));
}

// Paper §2, Figures 3-4: a profile with ~16k model and ~25k scan points reduced with w = 10
// gives similar counts (paper: 594 and 604) and similar neighbour-count histograms.
TEST(KCenter, ReproducesThePaperProfileFigures) {
  ProfileSpec spec = hat_profile(60, 85, 150, 90, 8);
  spec.width_mm = 195;
  const PointCloud model = testing::sample_profile(spec, 16230, 8);
  // The part sprang back: walls opened by 4 degrees, extra material, noise.
  ProfileSpec bent = spec;
  for (auto& a : bent.bend_angles_deg) a *= 86.0 / 90.0;
  bent.flange_lengths_mm.front() += 6.0;
  PointCloud scan = testing::sample_profile(bent, 25406, 9);
  testing::add_noise(scan.points, 0.05, 10);
  auto m = kcenter_reduce(model.points, {0, 10.0, 0, 128});
  auto s = kcenter_reduce(scan.points, {0, 10.0, 0, 128});
  ASSERT_TRUE(m && s);
  std::vector<Vec3> mc, sc;
  for (auto i : m->centers) mc.push_back(model.points[i]);
  for (auto i : s->centers) sc.push_back(scan.points[i]);
  const auto mh = count_histogram(neighbor_counts(mc, 10.0 * 2.0));
  const auto sh = count_histogram(neighbor_counts(sc, 10.0 * 2.0));
  std::cout << "[ paper §2 ] model " << model.size() << " -> " << mc.size() << " centers (w "
            << m->covering_radius_mm << "), scan " << scan.size() << " -> " << sc.size()
            << " centers (w " << s->covering_radius_mm << "); paper: 16230 -> 594, 25406 -> 604\n";
  std::cout << "[ Figure 4 ] centers with c neighbours within 2w, c: model scan\n";
  for (std::size_t c = 0; c < std::max(mh.size(), sh.size()); ++c)
    std::cout << "  " << c << ": " << (c < mh.size() ? mh[c] : 0) << " "
              << (c < sh.size() ? sh[c] : 0) << "\n";
  EXPECT_NEAR(static_cast<double>(mc.size()), 594.0, 594.0 * 0.25);
  EXPECT_NEAR(static_cast<double>(sc.size()) / static_cast<double>(mc.size()), 1.0, 0.1);
}

}  // namespace
}  // namespace springscan::analysis
