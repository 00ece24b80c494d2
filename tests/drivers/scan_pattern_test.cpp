// The simulated laser's scan pattern (simulators/scan_pattern.hpp) read back through the
// driver's conversion (drivers/conversion.hpp): a head looking straight down gets no return from
// vertical walls, a dual-head scanner (heads tilted about the travel) sees both, and every
// reading converts back onto the surface it came from.
#include "simulators/scan_pattern.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "drivers/conversion.hpp"
#include "drivers/messages.hpp"

namespace springscan::simulators {
namespace {

using analysis::Vec3;

// A floor (z = 0, x in [-30, 30]) with two walls (x = +-20, z in [0, 20]), 40 mm along y (the
// travel), sampled every 0.1 mm.
analysis::PointCloud channel() {
  analysis::PointCloud surface;
  for (double y = 0.0; y <= 40.0; y += 0.1) {
    for (double x = -30.0; x <= 30.0; x += 0.1) surface.points.emplace_back(x, y, 0.0);
    for (double z = 0.1; z <= 20.0; z += 0.1)
      for (double x : {-20.0, 20.0}) surface.points.emplace_back(x, y, z);
  }
  return surface;
}

// Every reading in part coordinates, through the wire format and the driver's conversion.
std::vector<Vec3> to_part(const std::vector<SimulatedProfile>& profiles,
                          const drivers::LaserCalibration& calibration) {
  std::vector<Vec3> out;
  for (std::size_t k = 0; k < profiles.size(); ++k) {
    const auto bytes = drivers::encode_laser_profile(static_cast<std::uint32_t>(k),
                                                     profiles[k].encoder_mm, 0, profiles[k].points);
    const auto view = drivers::decode_laser_profile(bytes);
    EXPECT_TRUE(view.ok()) << view.message();
    drivers::append_laser_profile(*view, calibration, out);
  }
  return out;
}

std::size_t wall_points(const std::vector<Vec3>& points, double x) {
  std::size_t n = 0;
  for (const Vec3& p : points) n += std::abs(p.x() - x) < 0.3 && p.z() > 2.0 && p.z() < 18.0;
  return n;
}

TEST(ScanPattern, DualHeadSeesTheWallsOneHeadMisses) {
  const analysis::PointCloud surface = channel();
  LaserPatternSettings settings;
  settings.step_mm = 1.0;
  settings.points_per_profile = 300;
  const NoiseSettings no_noise{.sigma_mm = 0.0};
  std::mt19937 rng(1);
  const auto one_head =
      to_part(laser_profiles(surface, settings, no_noise, rng), settings.calibration);
  EXPECT_LT(wall_points(one_head, 20.0) + wall_points(one_head, -20.0), 100u);

  settings.head_tilt_deg = 30.0;
  const auto profiles = laser_profiles(surface, settings, no_noise, rng);
  const auto two_heads = to_part(profiles, settings.calibration);
  EXPECT_GT(wall_points(two_heads, 20.0), 1000u);
  EXPECT_GT(wall_points(two_heads, -20.0), 1000u);
  // Readings land on the channel (float on the wire: a few micrometres).
  for (const Vec3& p : two_heads) {
    const double to_floor = std::abs(p.z());
    const double to_wall = std::min(std::abs(p.x() - 20.0), std::abs(p.x() + 20.0));
    ASSERT_LT(std::min(to_floor, to_wall), 0.01) << p.transpose();
  }
}

}  // namespace
}  // namespace springscan::simulators
