// A head's raw scan (simulators/parts/head_scan.hpp) of a plane 100 mm below it, whose ranges,
// coverage, encoder scale and outliers follow from the geometry.
#include "simulators/parts/head_scan.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

namespace springscan::parts {
namespace {

using analysis::Transform;
using analysis::Vec3;

/// The square [-10, 10]^2 at z = 0, two triangles.
analysis::TriangleMesh square() {
  analysis::TriangleMesh m;
  m.vertices = {Vec3(-10, -10, 0), Vec3(10, -10, 0), Vec3(10, 10, 0), Vec3(-10, 10, 0)};
  m.triangles = {{0, 1, 2}, {0, 2, 3}};
  return m;
}

/// Looking down from z = 100: head x = station x, range = -z, encoder = y.
HeadScanSettings above() {
  HeadScanSettings s;
  s.T_station_head.linear() << 1, 0, 0, 0, 0, 1, 0, -1, 0;
  s.T_station_head.translation() = Vec3(0, 0, 100);
  s.x_min_mm = -20;
  s.x_max_mm = 20;
  s.encoder_min_mm = -20;
  s.encoder_max_mm = 20;
  s.noise_sigma_mm = 0.0;
  return s;
}

TEST(HeadScan, RangesCoverageAndEncoderScale) {
  auto scan = head_scan(square(), above());
  ASSERT_TRUE(scan.ok()) << scan.message();
  // 1 mm spacing: 21 x 21 rays meet the square (edges included up to rounding).
  EXPECT_NEAR(static_cast<double>(scan->points.size()), 21.0 * 21.0, 21.0 * 2);
  for (const Vec3& p : scan->points) {
    EXPECT_NEAR(p.y(), 100.0, 1e-9);  // the range
    EXPECT_LE(std::abs(p.x()), 10.0 + 1e-9);
    EXPECT_LE(std::abs(p.z()), 10.0 + 1e-9);
  }
  // The encoder's true travel is twice its reading: only readings within +-5 mm reach the square.
  HeadScanSettings doubled = above();
  doubled.motion_scale = 2.0;
  scan = head_scan(square(), doubled);
  ASSERT_TRUE(scan.ok());
  for (const Vec3& p : scan->points) EXPECT_LE(std::abs(p.z()), 5.0 + 1e-9);
}

TEST(HeadScan, GrazingNoiseAndOutliers) {
  HeadScanSettings tilted = above();
  // Turned 85 degrees about x: the rays meet the plane beyond the 80 degree incidence limit.
  tilted.T_station_head.linear() =
      Eigen::AngleAxisd(85.0 * std::numbers::pi / 180.0, Vec3::UnitX()).toRotationMatrix() *
      tilted.T_station_head.linear();
  auto none = head_scan(square(), tilted);
  ASSERT_TRUE(none.ok());
  EXPECT_TRUE(none->points.empty());
  HeadScanSettings noisy = above();
  noisy.noise_sigma_mm = 0.02;
  noisy.outlier_fraction = 0.5;
  noisy.outlier_max_mm = 3.0;
  auto scan = head_scan(square(), noisy);
  ASSERT_TRUE(scan.ok());
  std::size_t far = 0;
  for (const Vec3& p : scan->points) far += std::abs(p.y() - 100.0) > 0.1 ? 1 : 0;
  // Half are outliers, uniform in +-3 mm: about 97 % of those lie beyond 0.1 mm.
  EXPECT_NEAR(static_cast<double>(far) / static_cast<double>(scan->points.size()), 0.5 * 0.967,
              0.06);
}

TEST(HeadScan, EmptyAndBadInput) {
  EXPECT_FALSE(head_scan(analysis::TriangleMesh{}, above()).ok());
  HeadScanSettings bad = above();
  bad.point_spacing_mm = 0.0;
  EXPECT_FALSE(head_scan(square(), bad).ok());
  bad = above();
  bad.outlier_fraction = 0.7;
  EXPECT_FALSE(head_scan(square(), bad).ok());
}

}  // namespace
}  // namespace springscan::parts
