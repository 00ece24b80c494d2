#include "analysis/preprocess/normals.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "tests/analysis/synthetic.hpp"

namespace springscan::analysis {
namespace {

TEST(Normals, PlaneNormalsAreExactAndFaceTheViewpoint) {
  // A tilted plane: every normal must be +-n, oriented towards the viewpoint above it.
  const Vec3 n = Vec3(0.2, -0.3, 1.0).normalized();
  const Vec3 u = n.unitOrthogonal(), v = n.cross(u);
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> c(-50, 50);
  std::vector<Vec3> points;
  for (int i = 0; i < 2000; ++i) points.push_back(c(rng) * u + c(rng) * v + Vec3(5, 6, 7));
  auto result = estimate_normals(points);
  ASSERT_TRUE(result) << result.message();
  EXPECT_EQ(result->undefined, 0u);
  for (std::size_t i = 0; i < points.size(); ++i) {
    EXPECT_NEAR(result->normals[i].dot(n), 1.0, 1e-9);
    EXPECT_NEAR(result->surface_variation[i], 0.0, 1e-12);
  }
}

TEST(Normals, RadiusVariantMatchesSurfaceNormalsOnACurvedPart) {
  const PointCloud part = testing::bumpy_surface(20000, 2);
  NormalSettings settings;
  settings.radius_mm = 2.0;
  auto result = estimate_normals(part.points, settings);
  ASSERT_TRUE(result) << result.message();
  double worst = 0.0;
  for (std::size_t i = 0; i < part.size(); ++i)
    worst = std::max(worst, std::acos(std::min(1.0, result->normals[i].dot(part.normals[i]))));
  EXPECT_LT(worst, 0.15);  // rad; the plane of a 2 mm patch on bumps of radius ~10 mm
}

TEST(Normals, OrientAlongReferenceFlipsToTheReferenceSide) {
  const PointCloud part = testing::bumpy_surface(5000, 3);
  NormalSettings settings;
  settings.orient_to_viewpoint = true;
  settings.viewpoint = Vec3(0, 0, -1e6);  // deliberately the wrong side
  auto result = estimate_normals(part.points, settings);
  ASSERT_TRUE(result);
  orient_along_reference(part.points, result->normals, KdTree(part.points), part.normals);
  for (std::size_t i = 0; i < part.size(); ++i)
    EXPECT_GT(result->normals[i].dot(part.normals[i]), 0.9);
}

TEST(Normals, TinyAndBadInputs) {
  auto empty = estimate_normals(std::vector<Vec3>{});
  ASSERT_TRUE(empty);
  EXPECT_TRUE(empty->normals.empty());
  auto two = estimate_normals(std::vector<Vec3>{Vec3(0, 0, 0), Vec3(1, 0, 0)});
  ASSERT_TRUE(two);
  EXPECT_EQ(two->undefined, 2u);
  EXPECT_EQ(two->normals[0], Vec3::Zero());
  auto nan = estimate_normals(std::vector<Vec3>{Vec3(0, 0, 0), Vec3(NAN, 0, 0), Vec3(0, 1, 0)});
  EXPECT_FALSE(nan);
  NormalSettings bad;
  bad.k_neighbors = 1;
  EXPECT_FALSE(estimate_normals(std::vector<Vec3>{Vec3(0, 0, 0)}, bad));
}

TEST(Normals, SameResultForAnyThreadCount) {
  const PointCloud part = testing::bumpy_surface(10000, 4);
  NormalSettings one, many;
  one.threads = 1;
  many.threads = 3;
  auto a = estimate_normals(part.points, one), b = estimate_normals(part.points, many);
  ASSERT_TRUE(a && b);
  EXPECT_EQ(a->normals, b->normals);
}

}  // namespace
}  // namespace springscan::analysis
