#include "analysis/preprocess/curvature.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "tests/analysis/synthetic.hpp"

namespace springscan::analysis {
namespace {

// Points on a sphere of radius r at (about) a fixed spacing, with exact outward normals.
PointCloud sphere(double radius_mm, double spacing_mm) {
  PointCloud cloud;
  const double golden = std::numbers::pi * (3.0 - std::sqrt(5.0));
  const auto n =
      static_cast<int>(4.0 * std::numbers::pi * radius_mm * radius_mm / (spacing_mm * spacing_mm));
  for (int i = 0; i < n; ++i) {
    const double z = 1.0 - 2.0 * (i + 0.5) / n;
    const double rho = std::sqrt(1.0 - z * z);
    const Vec3 u(rho * std::cos(golden * i), rho * std::sin(golden * i), z);
    cloud.points.push_back(radius_mm * u);
    cloud.normals.push_back(u);
  }
  return cloud;
}

double median(std::vector<double> v) {
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
  return v[v.size() / 2];
}

TEST(Curvature, ZeroOnAPlane) {
  PointCloud plane;
  std::mt19937 rng(41);
  std::uniform_real_distribution<double> u(0, 50);
  for (int i = 0; i < 3000; ++i) {
    plane.points.emplace_back(u(rng), u(rng), 3.0);
    plane.normals.push_back(Vec3::UnitZ());
  }
  const auto c = curvature_measure(KdTree(plane.points), plane.normals);
  for (double v : c) EXPECT_NEAR(v, 0.0, 1e-12);
}

TEST(Curvature, RisesAsSphereRadiusFallsAtEqualDensity) {
  // At spacing d the measure is about d / (2 R): halving R doubles it.
  double previous = 0.0;
  for (double radius : {80.0, 40.0, 20.0, 10.0}) {
    const PointCloud s = sphere(radius, 1.0);
    const double c = median(curvature_measure(KdTree(s.points), s.normals));
    EXPECT_GT(c, previous * 1.6) << "radius " << radius;
    EXPECT_NEAR(c, 1.0 / (2.0 * radius), 0.6 / (2.0 * radius)) << "radius " << radius;
    previous = c;
  }
}

TEST(Curvature, ReductionKeepsTheBendsOfAProfile) {
  // An L profile: flat legs go, the 5 mm bend stays (paper Figure 2).
  const PointCloud profile = testing::sample_profile(l_profile(60, 40, 90, 5), 20000, 42);
  CurvatureSettings s;
  auto r = reduce_by_curvature(profile, s);
  ASSERT_TRUE(r) << r.message();
  std::size_t on_bend = 0;
  for (auto i : r->kept) {
    const Vec3& p = profile.points[i];
    if (p.x() > 59.0 && p.z() < 6.0) ++on_bend;
  }
  EXPECT_GT(r->kept.size(), 200u);
  EXPECT_GT(static_cast<double>(on_bend), 0.8 * static_cast<double>(r->kept.size()));
  // With the k-center base sample, flat areas keep points too.
  s.base_kcenter_radius_mm = 10.0;
  auto merged = reduce_by_curvature(profile, s);
  ASSERT_TRUE(merged);
  EXPECT_GT(merged->kept.size(), r->kept.size() + 20);
}

TEST(Curvature, BadInputs) {
  PointCloud no_normals;
  no_normals.points = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)};
  EXPECT_FALSE(reduce_by_curvature(no_normals));
  PointCloud tiny = no_normals;
  tiny.normals.assign(3, Vec3::UnitZ());
  auto r = reduce_by_curvature(tiny);
  ASSERT_TRUE(r);
  EXPECT_TRUE(r->kept.empty());  // fewer than 3 neighbours each: C = 0
  tiny.points[1].x() = NAN;
  EXPECT_FALSE(reduce_by_curvature(tiny));
}

}  // namespace
}  // namespace springscan::analysis
