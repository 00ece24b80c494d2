#include "analysis/springback/relative_rotation.hpp"

#include <gtest/gtest.h>

#include <numbers>
#include <random>

namespace springscan::analysis {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

// The paper's Figure 8 axis and angle.
const Vec3 kPaperAxis = Vec3(-0.2614, 0.1958, 0.9452).normalized();
constexpr double kPaperAngleDeg = 8.8448;

TEST(RelativeRotation, IdentityHasNoAxis) {
  const AxisAngle r = axis_angle_of(Mat3::Identity());
  EXPECT_FALSE(r.axis_defined);
  EXPECT_EQ(r.angle_deg, 0.0);
}

TEST(RelativeRotation, AgreesWithEigenAngleAxisFromZeroTo180) {
  std::mt19937 rng(11);
  std::normal_distribution<double> g;
  for (double angle_deg :
       {1e-7, 1e-3, 0.5, kPaperAngleDeg, 45.0, 90.0, 135.0, 179.0, 179.999, 180.0 - 1e-7}) {
    for (int trial = 0; trial < 10; ++trial) {
      const Vec3 axis = Vec3(g(rng), g(rng), g(rng)).normalized();
      const Mat3 R = Eigen::AngleAxisd(angle_deg * kDeg, axis).toRotationMatrix();
      const AxisAngle ours = axis_angle_of(R);
      const Eigen::AngleAxisd eigen(R);
      ASSERT_TRUE(ours.axis_defined);
      EXPECT_NEAR(ours.angle_deg, angle_deg, 1e-9 + 1e-12 * angle_deg) << angle_deg;
      EXPECT_NEAR(ours.angle_deg, eigen.angle() / kDeg, 1e-6) << angle_deg;
      // The axis is good to about 1e-16 / angle (radians) near 0.
      EXPECT_NEAR((ours.axis - axis).norm(), 0.0, 1e-15 / (angle_deg * kDeg) + 1e-9) << angle_deg;
      // The paper's eigenvector property: R v = v.
      EXPECT_NEAR((R * ours.axis - ours.axis).norm(), 0.0, 1e-12);
    }
  }
}

TEST(RelativeRotation, HalfTurnGivesTheAxisUpToSign) {
  const Vec3 axis = Vec3(1, -2, 0.5).normalized();
  const AxisAngle r = axis_angle_of(Eigen::AngleAxisd(std::numbers::pi, axis).toRotationMatrix());
  EXPECT_NEAR(r.angle_deg, 180.0, 1e-9);
  EXPECT_NEAR(std::abs(r.axis.dot(axis)), 1.0, 1e-12);
}

TEST(RelativeRotation, SubsetBTurnedAboutThePaperAxis) {
  // Fit A needs no motion; subset B of the data is turned by alpha about v, so its fit turns
  // it back by -alpha (in the model frame, after the common motion T_a). The relative rotation
  // is B's turn relative to A: (v, alpha).
  const Transform T_a =
      Eigen::Translation3d(0.3, -0.1, 0.2) * Eigen::AngleAxisd(0.2, Vec3::UnitX());
  const Transform turn_b(Eigen::AngleAxisd(kPaperAngleDeg * kDeg, kPaperAxis));
  const Transform T_b = turn_b.inverse() * T_a;
  const AxisAngle r = relative_rotation(T_a, T_b);
  EXPECT_NEAR((r.axis - kPaperAxis).norm(), 0.0, 1e-12);
  EXPECT_NEAR(r.angle_deg, kPaperAngleDeg, 1e-10);
  // The paper's "last transformation" T_b T_a^-1 has the same angle and the reversed axis.
  const AxisAngle last = axis_angle_of((T_b * T_a.inverse()).linear());
  EXPECT_NEAR(last.angle_deg, kPaperAngleDeg, 1e-10);
}

}  // namespace
}  // namespace springscan::analysis
