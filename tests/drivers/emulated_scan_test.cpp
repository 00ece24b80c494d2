// The production libusb path against the simulator presented as a USB device by umockdev
// (simulators/usb_emulator.hpp). This binary is linked with libumockdev-preload, so libusb's
// sysfs reads and usbfs ioctls reach the emulated device once a testbed exists.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>

#include "drivers/laser_scanner.hpp"
#include "drivers/tactile_scanner.hpp"
#include "simulators/parts/sheet_part.hpp"
#include "simulators/usb_emulator.hpp"

namespace springscan {
namespace {

using analysis::ErrorCode;
using analysis::PointCloud;
using drivers::LaserLineScanner;
using drivers::TactileProbeScanner;
using parts::ProfileSpec;
using simulators::EmulatedUsbScanner;

constexpr double kSigmaMm = 0.02;

// A hat profile bent with a known springback: every surface faces the laser above it.
struct Part {
  ProfileSpec produced;
  PointCloud surface;  // dense, noise-free
};

const Part& part() {
  static const Part p = [] {
    const ProfileSpec nominal = parts::hat_profile(15, 20, 30, 45, 3);
    const std::vector<double> springback = {1.5, 1.5, 1.5, 1.5};
    Part out;
    out.produced = *parts::produced_profile(nominal, springback);
    parts::ScanSimulationSettings dense;
    dense.point_count = 120000;
    dense.noise_sigma_mm = 0.0;
    out.surface = *parts::simulate_scan(nominal, springback, dense);
    return out;
  }();
  return p;
}

simulators::ScannerDeviceSettings device_settings(drivers::protocol::ScannerKind kind) {
  simulators::ScannerDeviceSettings s;
  s.identity = {kind, "SIM-" + drivers::to_string(kind), "SN-TEST-7", "2.1.0"};
  s.noise.sigma_mm = kSigmaMm;
  s.laser.step_mm = 2.0;
  s.laser.points_per_profile = 256;
  s.probe.grid_step_mm = 4.0;
  s.probe.capture_radius_mm = 0.4;
  s.probe.stylus_radius_mm = 1.5f;
  s.probe.records_per_frame = 16;
  return s;
}

drivers::LinkSettings link_settings(drivers::protocol::ScannerKind kind) {
  drivers::LinkSettings link;
  link.usb.product_id = kind == drivers::protocol::ScannerKind::kLaserLine
                            ? drivers::protocol::kProductIdLaser
                            : drivers::protocol::kProductIdTactile;
  link.usb.serial = "SN-TEST-7";
  link.data_timeout_ms = 500;
  return link;
}

std::unique_ptr<EmulatedUsbScanner> emulate(const simulators::ScannerDeviceSettings& settings) {
  auto emulator = EmulatedUsbScanner::create(settings, part().surface);
  EXPECT_TRUE(emulator.ok()) << (emulator.ok() ? "" : emulator.message());
  return emulator.ok() ? std::move(emulator.value()) : nullptr;
}

std::unique_ptr<LaserLineScanner> laser_driver() {
  drivers::LaserScannerSettings s;
  s.link = link_settings(drivers::protocol::ScannerKind::kLaserLine);
  return std::make_unique<LaserLineScanner>(s);  // default calibration = the simulator's mount
}

// RMS and largest distance from the cloud to the produced part's exact surface.
struct Fit {
  double rms = 0.0;
  double max = 0.0;
};
Fit fit_to_part(const PointCloud& cloud) {
  const auto distance = parts::profile_surface_distance(part().produced);
  Fit f;
  for (const auto& q : cloud.points) {
    const double d = std::abs(distance->closest(q).signed_distance_mm);
    f.rms += d * d;
    f.max = std::max(f.max, d);
  }
  f.rms = std::sqrt(f.rms / double(std::max<std::size_t>(cloud.size(), 1)));
  return f;
}

TEST(EmulatedScanner, LaserScanMatchesThePartWithinTheNoise) {
  auto emulator = emulate(device_settings(drivers::protocol::ScannerKind::kLaserLine));
  ASSERT_TRUE(emulator);
  auto scanner = laser_driver();
  const auto info = scanner->identify();
  ASSERT_TRUE(info.ok()) << info.message();
  EXPECT_EQ(info->kind, "laser_line");
  EXPECT_EQ(info->serial, "SN-TEST-7");
  EXPECT_EQ(info->firmware, "2.1.0");
  std::vector<double> progress;
  const auto cloud = scanner->scan([&](double f) {
    progress.push_back(f);
    return true;
  });
  ASSERT_TRUE(cloud.ok()) << cloud.message();
  const auto& outcome = scanner->last_outcome();
  EXPECT_EQ(outcome.frames_received, outcome.started.expected_frames);
  EXPECT_NEAR(outcome.frames_received, 30, 1);  // 60 mm of width every 2 mm
  EXPECT_GT(cloud->size(), std::size_t(0.9 * outcome.started.expected_points));
  const Fit fit = fit_to_part(*cloud);
  // Noise is along the laser's range; the distance to a sloped surface is at most that.
  EXPECT_LT(fit.rms, 1.3 * kSigmaMm);
  EXPECT_GT(fit.rms, 0.4 * kSigmaMm);
  EXPECT_LT(fit.max, 6.0 * kSigmaMm);
  ASSERT_FALSE(progress.empty());
  EXPECT_TRUE(std::is_sorted(progress.begin(), progress.end()));
  EXPECT_DOUBLE_EQ(progress.back(), 1.0);
  EXPECT_TRUE(scanner->online());
}

TEST(EmulatedScanner, TactileScanCompensatesTheStylusRadius) {
  auto emulator = emulate(device_settings(drivers::protocol::ScannerKind::kTactileProbe));
  ASSERT_TRUE(emulator);
  drivers::TactileScannerSettings s;
  s.link = link_settings(drivers::protocol::ScannerKind::kTactileProbe);
  TactileProbeScanner scanner(s);
  const auto cloud = scanner.scan(nullptr);
  ASSERT_TRUE(cloud.ok()) << cloud.message();
  EXPECT_GT(cloud->size(), 200u);
  ASSERT_EQ(cloud->normals.size(), cloud->size());
  EXPECT_NEAR(cloud->normals[0].z(), 1.0, 1e-6);  // probed from above
  const Fit fit = fit_to_part(*cloud);
  EXPECT_LT(fit.rms, 1.3 * kSigmaMm);
  EXPECT_LT(fit.max, 6.0 * kSigmaMm);
  // Without the compensation the points would sit a stylus radius (1.5 mm) off the surface.
  EXPECT_GT(fit.rms, 0.3 * kSigmaMm);
}

TEST(EmulatedScanner, UnplugMidScanFailsWithoutPartialResultThenReconnects) {
  auto settings = device_settings(drivers::protocol::ScannerKind::kLaserLine);
  settings.faults.unplug_at_fraction = 0.5;
  settings.scan_duration_s = 0.3;  // paced, so the unplug comes well after the scan started
  auto emulator = emulate(settings);
  ASSERT_TRUE(emulator);
  auto scanner = laser_driver();
  const auto failed = scanner->scan(nullptr);
  ASSERT_FALSE(failed.ok());
  EXPECT_EQ(failed.code(), ErrorCode::kDeviceGone) << failed.error().to_string();
  EXPECT_NE(failed.message().find("no partial result"), std::string::npos) << failed.message();
  EXPECT_FALSE(scanner->online());
  const auto absent = scanner->identify();  // nothing to talk to while unplugged
  ASSERT_FALSE(absent.ok());
  EXPECT_EQ(absent.code(), ErrorCode::kNotFound) << absent.error().to_string();
  emulator->set_faults({});
  emulator->plug();
  const auto cloud = scanner->scan(nullptr);
  ASSERT_TRUE(cloud.ok()) << cloud.message();
  EXPECT_EQ(scanner->last_outcome().frames_received,
            scanner->last_outcome().started.expected_frames);
  EXPECT_GE(scanner->link().usb_stats().opens, 2u);
  EXPECT_LT(fit_to_part(*cloud).rms, 1.3 * kSigmaMm);
}

TEST(EmulatedScanner, StalledDeviceTimesOutAndTheNextScanWorks) {
  auto settings = device_settings(drivers::protocol::ScannerKind::kLaserLine);
  settings.faults.stall_at_fraction = 0.3;
  auto emulator = emulate(settings);
  ASSERT_TRUE(emulator);
  auto scanner = laser_driver();
  const auto failed = scanner->scan(nullptr);
  ASSERT_FALSE(failed.ok());
  EXPECT_EQ(failed.code(), ErrorCode::kTimeout) << failed.error().to_string();
  EXPECT_NE(failed.message().find("at frame 9 of 3"), std::string::npos) << failed.message();
  const auto cloud = scanner->scan(nullptr);
  ASSERT_TRUE(cloud.ok()) << cloud.message();
  EXPECT_EQ(emulator->scans_started(), 2u);
}

TEST(EmulatedScanner, CorruptFrameFailsTheScanAndTheNextScanWorks) {
  auto settings = device_settings(drivers::protocol::ScannerKind::kLaserLine);
  settings.faults.corrupt_crc_at_fraction = 0.5;
  auto emulator = emulate(settings);
  ASSERT_TRUE(emulator);
  auto scanner = laser_driver();
  const auto failed = scanner->scan(nullptr);
  ASSERT_FALSE(failed.ok());
  EXPECT_EQ(failed.code(), ErrorCode::kBadCrc) << failed.error().to_string();
  const auto cloud = scanner->scan(nullptr);
  ASSERT_TRUE(cloud.ok()) << cloud.message();
  EXPECT_EQ(scanner->last_outcome().frames_received,
            scanner->last_outcome().started.expected_frames);
}

TEST(EmulatedScanner, SequenceGapFailsTheScan) {
  auto settings = device_settings(drivers::protocol::ScannerKind::kTactileProbe);
  settings.faults.wrong_sequence_at_fraction = 0.5;
  auto emulator = emulate(settings);
  ASSERT_TRUE(emulator);
  drivers::TactileScannerSettings s;
  s.link = link_settings(drivers::protocol::ScannerKind::kTactileProbe);
  TactileProbeScanner scanner(s);
  const auto failed = scanner.scan(nullptr);
  ASSERT_FALSE(failed.ok());
  EXPECT_EQ(failed.code(), ErrorCode::kSequenceGap) << failed.error().to_string();
  EXPECT_TRUE(scanner.scan(nullptr).ok());
}

TEST(EmulatedScanner, MissingProfileIsASequenceGapAndTheNextScanWorks) {
  auto settings = device_settings(drivers::protocol::ScannerKind::kLaserLine);
  settings.faults.skip_frame_at_fraction = 0.5;  // frame sequence intact, profile index jumps
  auto emulator = emulate(settings);
  ASSERT_TRUE(emulator);
  auto scanner = laser_driver();
  const auto failed = scanner->scan(nullptr);
  ASSERT_FALSE(failed.ok());
  EXPECT_EQ(failed.code(), ErrorCode::kSequenceGap) << failed.error().to_string();
  EXPECT_NE(failed.message().find("out of order"), std::string::npos) << failed.message();
  EXPECT_TRUE(scanner->scan(nullptr).ok());
}

TEST(EmulatedScanner, MissingProbeBatchIsASequenceGap) {
  auto settings = device_settings(drivers::protocol::ScannerKind::kTactileProbe);
  settings.faults.skip_frame_at_fraction = 0.5;
  auto emulator = emulate(settings);
  ASSERT_TRUE(emulator);
  drivers::TactileScannerSettings s;
  s.link = link_settings(drivers::protocol::ScannerKind::kTactileProbe);
  TactileProbeScanner scanner(s);
  const auto failed = scanner.scan(nullptr);
  ASSERT_FALSE(failed.ok());
  EXPECT_EQ(failed.code(), ErrorCode::kSequenceGap) << failed.error().to_string();
}

TEST(EmulatedScanner, EndpointHaltThatCannotBeClearedIsAStalledEndpoint) {
  auto settings = device_settings(drivers::protocol::ScannerKind::kLaserLine);
  settings.faults.halt_at_fraction = 0.4;
  settings.faults.halt_sticks = true;
  auto emulator = emulate(settings);
  ASSERT_TRUE(emulator);
  auto scanner = laser_driver();
  const auto failed = scanner->scan(nullptr);
  ASSERT_FALSE(failed.ok());
  EXPECT_EQ(failed.code(), ErrorCode::kStalledEndpoint) << failed.error().to_string();
  EXPECT_NE(failed.message().find("no partial result"), std::string::npos) << failed.message();
  EXPECT_EQ(emulator->stats().halts_cleared, 0u);
  // A power cycle (replug) recovers the device.
  emulator->unplug();
  EXPECT_FALSE(scanner->scan(nullptr).ok());  // the driver notices that the device is gone
  emulator->set_faults({});
  emulator->plug();
  const auto cloud = scanner->scan(nullptr);
  ASSERT_TRUE(cloud.ok()) << cloud.error().to_string();
  EXPECT_EQ(scanner->last_outcome().frames_received,
            scanner->last_outcome().started.expected_frames);
}

TEST(EmulatedScanner, StalledEndpointIsClearedAndTheScanCompletes) {
  auto settings = device_settings(drivers::protocol::ScannerKind::kLaserLine);
  settings.faults.halt_at_fraction = 0.4;
  auto emulator = emulate(settings);
  ASSERT_TRUE(emulator);
  auto scanner = laser_driver();
  const auto cloud = scanner->scan(nullptr);
  ASSERT_TRUE(cloud.ok()) << cloud.message();
  EXPECT_EQ(scanner->last_outcome().frames_received,
            scanner->last_outcome().started.expected_frames);
  EXPECT_EQ(scanner->link().usb_stats().stalls_cleared, 1u);
  EXPECT_EQ(emulator->stats().halts_cleared, 1u);
  EXPECT_LT(fit_to_part(*cloud).rms, 1.3 * kSigmaMm);
}

TEST(EmulatedScanner, CancelStopsTheDeviceAndTheNextScanWorks) {
  auto emulator = emulate(device_settings(drivers::protocol::ScannerKind::kLaserLine));
  ASSERT_TRUE(emulator);
  auto scanner = laser_driver();
  const auto cancelled = scanner->scan([](double f) { return f < 0.3; });
  ASSERT_FALSE(cancelled.ok());
  EXPECT_EQ(cancelled.code(), ErrorCode::kCancelled) << cancelled.error().to_string();
  EXPECT_TRUE(scanner->scan(nullptr).ok());
}

TEST(EmulatedScanner, WrongKindAndWrongSerialAreRefused) {
  auto emulator = emulate(device_settings(drivers::protocol::ScannerKind::kLaserLine));
  ASSERT_TRUE(emulator);
  drivers::TactileScannerSettings t;
  t.link = link_settings(drivers::protocol::ScannerKind::kLaserLine);  // finds the laser
  const auto kind = TactileProbeScanner(t).identify();
  ASSERT_FALSE(kind.ok());
  EXPECT_EQ(kind.code(), ErrorCode::kInvalidSettings) << kind.error().to_string();
  EXPECT_NE(kind.message().find("needs a tactile_probe"), std::string::npos) << kind.message();
  drivers::LaserScannerSettings l;
  l.link = link_settings(drivers::protocol::ScannerKind::kLaserLine);
  l.link.usb.serial = "SN-OTHER";
  const auto serial = LaserLineScanner(l).identify();
  ASSERT_FALSE(serial.ok());
  EXPECT_EQ(serial.code(), ErrorCode::kNotFound) << serial.error().to_string();
  EXPECT_NE(serial.message().find("SN-TEST-7"), std::string::npos) << serial.message();
}

}  // namespace
}  // namespace springscan
