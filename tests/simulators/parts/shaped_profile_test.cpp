#include "simulators/parts/shaped_profile.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

namespace springscan::analysis {
using namespace springscan::parts;  // test and demo parts (simulators/parts)
namespace {

using Vec2 = Eigen::Vector2d;
constexpr double kDeg = std::numbers::pi / 180.0;

// Unit tangents (direction of travel) at the start and the end of an element.
Vec2 tangent_at(const ProfileElement& e, bool at_end) {
  if (e.kind == ProfileElement::Kind::kLine) return (e.end - e.start).normalized();
  const Vec2 radial = ((at_end ? e.end : e.start) - e.center).normalized();
  const Vec2 left(-radial.y(), radial.x());
  return e.sweep_rad > 0.0 ? left : Vec2(-left);
}

double angle_between_deg(const Vec2& a, const Vec2& b) {
  return std::atan2(std::abs(a.x() * b.y() - a.y() * b.x()), a.dot(b)) / kDeg;
}

// The hat the accuracy tests use: brims, curled walls, a top; springback varying along y.
ProfileShape curled_hat_shape() {
  ProfileShape shape;
  shape.springback_deg = {1.0, 2.0, -0.5, 1.5};
  shape.springback_gradient_deg_per_100mm = {0.5, 0.0, -1.0, 0.25};
  shape.curl_radius_mm = {0, 180, 0, -400, 0};
  shape.twist_deg_per_100mm = 0.4;
  return shape;
}

TEST(ShapedProfile, SectionIsTangentContinuousAndBendsTurnAsTheTruthSays) {
  const ProfileSpec hat = hat_profile(25, 60, 45, 90, 4);
  const ProfileShape shape = curled_hat_shape();
  for (double y : {0.0, 17.0, 60.0}) {
    const auto path = shaped_section(hat, shape, y);
    ASSERT_TRUE(path.ok()) << path.message();
    ASSERT_EQ(path->size(), 9u);
    for (std::size_t i = 1; i < path->size(); ++i) {
      EXPECT_NEAR(((*path)[i].start - (*path)[i - 1].end).norm(), 0.0, 1e-12);
      EXPECT_NEAR((tangent_at((*path)[i], false) - tangent_at((*path)[i - 1], true)).norm(), 0.0,
                  1e-12);
    }
    for (int b = 0; b < 4; ++b) {
      // The angle between the tangents of the flanges' ends next to the bend.
      const Vec2 before = tangent_at((*path)[2 * b], true),
                 after = tangent_at((*path)[2 * b + 2], false);
      EXPECT_NEAR(angle_between_deg(before, after), shaped_bend_angle_deg(hat, shape, b, y), 1e-9);
      const double springback =
          shape.springback_deg[b] + shape.springback_gradient_deg_per_100mm[b] * (y - 30.0) / 100.0;
      // Each curled neighbour takes half its sweep (length / radius) off the bend's turn.
      const auto sweep_deg = [&](int f) {
        const double rho = shape.curl_radius_mm[static_cast<std::size_t>(f)];
        return rho == 0.0 ? 0.0 : hat.flange_lengths_mm[static_cast<std::size_t>(f)] / rho / kDeg;
      };
      const double a = hat.bend_angles_deg[static_cast<std::size_t>(b)];
      const double turn =
          a - (a > 0 ? springback : -springback) - 0.5 * (sweep_deg(b) + sweep_deg(b + 1));
      EXPECT_NEAR(shaped_bend_angle_deg(hat, shape, b, y), std::abs(turn), 1e-9);
    }
    // A curled wall keeps its length and lies on a circle of its radius, centred to its left
    // for a positive radius.
    const ProfileElement& wall = (*path)[2];
    EXPECT_EQ(wall.kind, ProfileElement::Kind::kArc);
    EXPECT_NEAR(wall.radius_mm, 180.0, 1e-12);
    EXPECT_GT(wall.sweep_rad, 0.0);
    EXPECT_NEAR(wall.length_mm(), 60.0, 1e-9);
    EXPECT_NEAR((*path)[6].radius_mm, 400.0, 1e-12);
    EXPECT_LT((*path)[6].sweep_rad, 0.0);
  }
}

// The twist rate from the sections themselves: each flange's chord direction at y and y + dy.
TEST(ShapedProfile, FlangeTwistMatchesTheSections) {
  const ProfileSpec hat = hat_profile(25, 60, 45, 90, 4);
  const ProfileShape shape = curled_hat_shape();
  constexpr double kDy = 1.0;
  const auto a = shaped_section(hat, shape, 20.0), b = shaped_section(hat, shape, 20.0 + kDy);
  ASSERT_TRUE(a.ok() && b.ok());
  for (int f = 0; f < 5; ++f) {
    const Vec2 ca = ((*a)[2 * f].end - (*a)[2 * f].start).normalized();
    const Vec2 cb = ((*b)[2 * f].end - (*b)[2 * f].start).normalized();
    // Heading change along +y (left positive) is a left-handed turn about +y.
    const double heading_change_deg =
        std::atan2(ca.x() * cb.y() - ca.y() * cb.x(), ca.dot(cb)) / kDeg;
    EXPECT_NEAR(-heading_change_deg / kDy * 100.0, shaped_flange_twist_deg_per_100mm(hat, shape, f),
                1e-9)
        << "flange " << f;
  }
  EXPECT_NEAR(shaped_flange_twist_deg_per_100mm(hat, shape, 0), 0.4, 1e-12);
  EXPECT_NEAR(shaped_flange_twist_deg_per_100mm(hat, shape, 1), 0.4 + 0.5, 1e-12);
  EXPECT_NEAR(shaped_flange_twist_deg_per_100mm(hat, shape, 4), 0.4 + 0.5 + 0 + 1.0 + 0.25, 1e-12);
}

TEST(ShapedProfile, WithoutShapeItIsTheProducedProfile) {
  const ProfileSpec z = z_profile(30, 40, 70, 3);
  ProfileShape shape;
  shape.springback_deg = {0.7, -0.3};
  ScanSimulationSettings st;
  st.point_count = 2000;
  st.noise_sigma_mm = 0.0;
  const auto scan = simulate_shaped_scan(z, shape, st);
  ASSERT_TRUE(scan.ok()) << scan.message();
  const auto produced = produced_profile(z, shape.springback_deg);
  ASSERT_TRUE(produced.ok());
  const auto distance = profile_surface_distance(*produced);
  for (const Vec3& p : scan->points)
    EXPECT_NEAR(distance->closest(p).signed_distance_mm, 0.0, 1e-9);
}

TEST(ShapedProfile, RejectsShapesItCannotBuild) {
  const ProfileSpec l = l_profile(40, 30, 90, 3);
  ProfileShape sizes, closed, tight, gone;
  sizes.springback_deg = {1, 2};   // one bend
  closed.springback_deg = {95};    // turns the other way
  tight.curl_radius_mm = {10, 0};  // 40 mm on r 10
  gone.length_change_mm = {0, -30};
  for (const ProfileShape& bad : {sizes, closed, tight, gone})
    EXPECT_FALSE(shaped_section(l, bad, 0).ok());
  EXPECT_FALSE(simulate_shaped_scan(l, {}, {.point_count = 0}).ok());
  EXPECT_TRUE(simulate_shaped_scan(l, {}, {.point_count = 10}).ok());
}

// A length change moves the free edge along the flange by that much.
TEST(ShapedProfile, LengthChangeMovesTheFreeEdge) {
  const ProfileSpec l = l_profile(40, 30, 90, 3);
  ProfileShape longer;
  longer.length_change_mm = {0, 0.3};
  const auto path = shaped_section(l, longer, 10);
  ASSERT_TRUE(path.ok());
  EXPECT_NEAR((path->back().end - profile_path(l).back().end - Vec2(0, 0.3)).norm(), 0.0, 1e-12);
}

}  // namespace
}  // namespace springscan::analysis
