#include "simulators/parts/sheet_profile.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

namespace springscan::analysis {
using namespace springscan::parts;  // test and demo parts (simulators/parts)
namespace {

TEST(SheetProfile, RejectsInconsistentSpecs) {
  EXPECT_FALSE(is_valid(ProfileSpec{}));
  EXPECT_FALSE(is_valid({{10, 10}, {}, {}}));
  EXPECT_FALSE(is_valid({{10, 10}, {180}, {2}}));
  EXPECT_FALSE(is_valid({{10, -1}, {90}, {2}}));
  EXPECT_TRUE(is_valid(l_profile(40, 30, 90, 3)));
}

TEST(SheetProfile, LProfileEndsWhereGeometrySaysItShould) {
  // 40 mm along +x, a 90 degree left turn of radius 3, then 30 mm along +z.
  const auto path = profile_path(l_profile(40, 30, 90, 3));
  ASSERT_EQ(path.size(), 3u);
  EXPECT_TRUE(path[1].center.isApprox(Eigen::Vector2d(40, 3)));
  EXPECT_NEAR((path[2].end - Eigen::Vector2d(43, 33)).norm(), 0.0, 1e-12);
  EXPECT_NEAR(path[1].length_mm(), 3 * std::numbers::pi / 2, 1e-12);
}

TEST(SheetProfile, PathIsContinuousAndHatEndsLevel) {
  const auto path = profile_path(hat_profile(20, 30, 40, 90, 4));
  ASSERT_EQ(path.size(), 9u);
  for (std::size_t i = 1; i < path.size(); ++i)
    EXPECT_NEAR((path[i].start - path[i - 1].end).norm(), 0.0, 1e-12);
  // Turns of +90 -90 -90 +90 leave the last brim heading +x again, at the starting height.
  const auto& last = path.back();
  EXPECT_NEAR(last.end.y() - last.start.y(), 0.0, 1e-12);
  EXPECT_GT(last.end.x() - last.start.x(), 0.0);
  EXPECT_NEAR(last.end.y(), 0.0, 1e-12);
}

}  // namespace
}  // namespace springscan::analysis
