// The GenICam driver against the simulated profiler (simulators/genicam_camera.hpp) in this
// process, over real GigE Vision on the loopback interface: points against the range image the
// test builds, a camera that vanishes mid-scan and comes back, a camera that lacks a feature.
#include "drivers/genicam/genicam_scanner.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <fstream>
#include <sstream>
#include <thread>

#include "simulators/genicam_camera.hpp"

namespace springscan::drivers::genicam {
namespace {

constexpr int kWidth = 50, kLines = 40;
constexpr double kX0 = -10.0, kDx = 0.5, kStep = 0.5;

bool hole(int line, int i) { return (line * kWidth + i) % 7 == 3; }

// Range varies along and across the line, with holes (no return) at known pixels.
simulators::RangeImage test_image() {
  simulators::RangeImage im;
  im.width = kWidth;
  im.lines = kLines;
  im.x0_mm = kX0;
  im.dx_mm = kDx;
  for (int line = 0; line < kLines; ++line)
    for (int i = 0; i < kWidth; ++i)
      im.range_mm.push_back(hole(line, i) ? NAN : float(120.0 + 0.1 * i + 0.2 * line));
  return im;
}

GenicamSettings driver_settings() {
  GenicamSettings s;
  s.camera_id = "127.0.0.1";
  s.line_step_mm = kStep;
  s.lines_per_frame = 8;
  s.scan_lines = kLines;
  s.frame_timeout_ms = 500;
  return s;
}

std::unique_ptr<simulators::GenicamCamera> start(simulators::GenicamCameraSettings s = {}) {
  s.frame_period_us = 1000;
  auto camera = simulators::GenicamCamera::start(s, test_image());
  if (!camera) ADD_FAILURE() << camera.message();
  return camera ? std::move(*camera) : nullptr;
}

void expect_scan_of_test_image(const analysis::PointCloud& cloud) {
  std::size_t expected = 0;
  for (int line = 0; line < kLines; ++line)
    for (int i = 0; i < kWidth; ++i) expected += hole(line, i) ? 0 : 1;
  ASSERT_EQ(cloud.size(), expected);
  // Default head: x along x, motion along y, range down from z = 200. Every point must be the
  // truth of some pixel; the quantisation of C16 at scale 0.004 mm is 0.002 mm.
  for (const auto& p : cloud.points) {
    const int i = static_cast<int>(std::lround((p.x() - kX0) / kDx));
    const int line = static_cast<int>(std::lround(p.y() / kStep));
    ASSERT_TRUE(i >= 0 && i < kWidth && line >= 0 && line < kLines) << p.transpose();
    ASSERT_FALSE(hole(line, i));
    EXPECT_NEAR(p.x(), kX0 + i * kDx, 1e-9);
    EXPECT_NEAR(p.y(), line * kStep, 1e-9);
    EXPECT_NEAR(p.z(), 200.0 - (120.0 + 0.1 * i + 0.2 * line), 0.0021);
  }
}

TEST(GenicamScanner, ScansTheSimulatedProfilerOverGigEVision) {
  auto camera = start();
  ASSERT_TRUE(camera);
  GenicamScanner scanner(driver_settings());
  const auto info = scanner.identify();
  ASSERT_TRUE(info) << info.message();
  EXPECT_EQ(info->serial, "SIM-GENICAM-1");
  EXPECT_EQ(info->kind, "laser_line");
  EXPECT_TRUE(scanner.online());
  for (int pass = 0; pass < 2; ++pass) {  // the second pass sees the part from its start again
    double last_progress = 0.0;
    const auto cloud = scanner.scan([&](double f) { return last_progress = f, true; });
    ASSERT_TRUE(cloud) << cloud.message();
    expect_scan_of_test_image(*cloud);
    EXPECT_DOUBLE_EQ(last_progress, 1.0);
    EXPECT_EQ(scanner.last_outcome().lost_frames, 0);
    EXPECT_EQ(scanner.last_outcome().lines, kLines);
  }
}

TEST(GenicamScanner, CameraGoneMidScanIsDeviceGoneAndComesBack) {
  simulators::GenicamCameraSettings s;
  s.vanish_after_lines = 16;  // after two of the five frames
  s.return_after_s = 3.0;     // after the driver has given up on it (timeout + no answer)
  auto camera = start(s);
  ASSERT_TRUE(camera);
  GenicamScanner scanner(driver_settings());
  const auto failed = scanner.scan({});
  ASSERT_FALSE(failed);
  EXPECT_EQ(failed.code(), analysis::ErrorCode::kDeviceGone) << failed.message();
  EXPECT_FALSE(scanner.online()) << failed.message();
  // identify() reopens it once it is back (as the daemon's probe does after an unplug).
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(20);
  while (!scanner.identify() && std::chrono::steady_clock::now() < deadline)
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  ASSERT_TRUE(scanner.online());
  const auto cloud = scanner.scan({});
  ASSERT_TRUE(cloud) << cloud.message();
  expect_scan_of_test_image(*cloud);
}

TEST(GenicamScanner, MissingFeatureIsNamed) {
  std::ifstream in(simulators::default_genicam_xml());
  std::stringstream xml;
  xml << in.rdbuf();
  std::string text = xml.str();
  // The camera without Scan3dCoordinateOffset: rename the feature node and its category entry.
  for (std::size_t at = 0; (at = text.find(">Scan3dCoordinateOffset<", at)) != std::string::npos;)
    text.replace(at, 24, ">Scan3dCoordinateOffsetX<");
  const std::string renamed = "Name=\"Scan3dCoordinateOffset\"";
  ASSERT_NE(text.find(renamed), std::string::npos);
  text.replace(text.find(renamed), renamed.size(), "Name=\"Scan3dCoordinateOffsetX\"");
  const std::string path = ::testing::TempDir() + "genicam_no_offset.xml";
  std::ofstream(path) << text;
  simulators::GenicamCameraSettings s;
  s.genicam_xml = path;
  auto camera = start(s);
  ASSERT_TRUE(camera);
  GenicamScanner scanner(driver_settings());
  const auto info = scanner.identify();
  ASSERT_FALSE(info);
  EXPECT_EQ(info.code(), analysis::ErrorCode::kInvalidSettings);
  EXPECT_NE(info.message().find("Scan3dCoordinateOffset"), std::string::npos) << info.message();
  EXPECT_EQ(info.message().find("Scan3dCoordinateScale"), std::string::npos) << info.message();
}

}  // namespace
}  // namespace springscan::drivers::genicam
