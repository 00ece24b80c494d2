// The simulated laser's scan pattern (simulators/scan_pattern.hpp) read back through the
// driver's conversion (drivers/conversion.hpp): a head looking straight down gets no return from
// vertical walls, a dual-head scanner (heads tilted about the travel) sees both, and every
// reading converts back onto the surface it came from.
#include "simulators/scan_pattern.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "drivers/conversion.hpp"
#include "drivers/messages.hpp"
#include "simulators/scanner_device.hpp"

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

// A part placed anew for each scan (the gauge studies' re-placement): a rigid motion within the
// limits set, a new one each time, none when the limits are 0.
TEST(ReplacedPart, EachScanPlacesThePartAnewWithinTheLimitsAndRigidly) {
  analysis::PointCloud surface;  // every 100th point of the channel: its shape, cheaply
  const analysis::PointCloud dense = channel();
  for (std::size_t i = 0; i < dense.points.size(); i += 100)
    surface.points.push_back(dense.points[i]);
  ScannerDeviceSettings settings;
  std::mt19937 rng(7);
  const analysis::PointCloud same = replaced(surface, settings, rng);
  ASSERT_EQ(same.points.size(), surface.points.size());
  EXPECT_EQ(same.points.front(), surface.points.front());
  EXPECT_EQ(same.points.back(), surface.points.back());

  settings.replace_mm = 2.0;
  settings.replace_deg = 1.0;
  Vec3 centroid = Vec3::Zero();
  for (const auto& p : surface.points) centroid += p;
  centroid /= double(surface.points.size());
  const std::size_t a = 0, b = surface.points.size() / 2, c = surface.points.size() - 1;
  double largest_turn = 0.0, largest_shift = 0.0;
  Vec3 previous_first = surface.points[a];
  for (int k = 0; k < 40; ++k) {
    const analysis::PointCloud moved = replaced(surface, settings, rng);
    // Rigid: distances kept (three points fix the motion).
    for (auto [i, j] : {std::pair{a, b}, std::pair{b, c}, std::pair{a, c}}) {
      EXPECT_NEAR((moved.points[i] - moved.points[j]).norm(),
                  (surface.points[i] - surface.points[j]).norm(), 1e-9);
    }
    // The turn from two directions of the part, the shift at the centroid (about which it turns).
    const Vec3 u0 = (surface.points[b] - surface.points[a]).normalized();
    const Vec3 u1 = (moved.points[b] - moved.points[a]).normalized();
    const Vec3 v0 = (surface.points[c] - surface.points[a]).normalized();
    const Vec3 v1 = (moved.points[c] - moved.points[a]).normalized();
    const double turn_deg = std::max(std::acos(std::clamp(u0.dot(u1), -1.0, 1.0)),
                                     std::acos(std::clamp(v0.dot(v1), -1.0, 1.0))) *
                            180.0 / M_PI;
    Vec3 moved_centroid = Vec3::Zero();
    for (const auto& p : moved.points) moved_centroid += p;
    moved_centroid /= double(moved.points.size());
    const Vec3 shift = moved_centroid - centroid;
    EXPECT_LE(turn_deg, 1.0 + 1e-9);
    EXPECT_LE(shift.cwiseAbs().maxCoeff(), 2.0 + 1e-9);
    largest_turn = std::max(largest_turn, turn_deg);
    largest_shift = std::max(largest_shift, shift.cwiseAbs().maxCoeff());
    EXPECT_NE(moved.points[a], previous_first);  // a new placement each time
    previous_first = moved.points[a];
  }
  // The draws reach across the limits, not a corner of them.
  EXPECT_GT(largest_turn, 0.5);
  EXPECT_GT(largest_shift, 1.5);
}

}  // namespace
}  // namespace springscan::simulators
