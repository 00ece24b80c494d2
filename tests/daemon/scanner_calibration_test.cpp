// The scanner section of the daemon config reaches the points the station analyses. The
// daemon builds its driver the one way there is, drivers::make_scanner on the config as
// loaded (daemon/main.cpp), so a laser calibration or a tactile t_part_machine that is not the
// identity moves every analysed point by exactly that transform. The device is the scanner
// simulator behind the emulated USB bus (simulators/usb_emulator.hpp), without noise, so two
// scans of it agree point for point; the reference scan is taken by a driver with the default
// calibration (the simulator's own mount) and transformed by hand.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <fstream>
#include <mutex>
#include <numbers>
#include <sstream>
#include <thread>

#include "daemon/config.hpp"
#include "daemon/station.hpp"
#include "drivers/laser_scanner.hpp"
#include "drivers/scanner_proto.hpp"
#include "drivers/tactile_scanner.hpp"
#include "simulators/parts/sheet_part.hpp"
#include "simulators/plc_client.hpp"
#include "simulators/usb_emulator.hpp"
#include "test_rig.hpp"

namespace springscan::daemon {
namespace {

using drivers::protocol::ScannerKind;
using testing::TempDir;

constexpr const char* kSerial = "SN-CAL-1";

// A hat profile as the simulator scans it (dense, exact).
analysis::PointCloud hat_surface() {
  const parts::ProfileSpec nominal = parts::hat_profile(15, 20, 30, 45, 3);
  parts::ScanSimulationSettings dense;
  dense.point_count = 60000;
  dense.noise_sigma_mm = 0.0;
  return *parts::simulate_scan(nominal, {1.5, 1.5, 1.5, 1.5}, dense);
}

simulators::ScannerDeviceSettings device(ScannerKind kind) {
  simulators::ScannerDeviceSettings s;
  s.identity = {kind, "SIM", kSerial, "2.1.0"};
  s.noise.sigma_mm = 0.0;  // two scans then give the same points
  s.laser.step_mm = 3.0;
  s.laser.points_per_profile = 128;
  s.probe.grid_step_mm = 6.0;
  s.probe.capture_radius_mm = 0.4;
  s.probe.records_per_frame = 16;
  return s;
}

// A rigid motion that is clearly not the identity: 30 deg about a tilted axis and a shift.
analysis::Transform calibration_motion() {
  analysis::Transform T = analysis::Transform::Identity();
  T.linear() =
      Eigen::AngleAxisd(std::numbers::pi / 6.0, analysis::Vec3(1, 2, 3).normalized()).matrix();
  T.translation() = analysis::Vec3(5.0, -3.0, 12.0);
  return T;
}

std::string vec(const char* name, const analysis::Vec3& v) {
  std::ostringstream s;
  s.precision(17);
  s << name << " { x: " << v.x() << " y: " << v.y() << " z: " << v.z() << " } ";
  return s.str();
}

// The laser's default mount (drivers/conversion.hpp) moved by T: p' = T p for every profile point.
std::string laser_section(const analysis::Transform& T) {
  const drivers::LaserCalibration d;
  return "scanner { kind: LASER_LINE laser_calibration { " + vec("origin_mm", T * d.origin_mm) +
         vec("x_axis", T.linear() * d.x_axis) + vec("z_axis", T.linear() * d.z_axis) +
         vec("motion_axis", T.linear() * d.motion_axis) + "} ";
}

std::string tactile_section(const analysis::Transform& T) {
  std::ostringstream s;
  s.precision(17);
  s << "scanner { kind: TACTILE_PROBE ";
  for (int i = 0; i < 16; ++i) s << "t_part_machine: " << T.matrix()(i / 4, i % 4) << " ";
  return s.str();
}

/// Loads `scanner_section` through the daemon's config loader, builds the driver with
/// drivers::make_scanner as springscand does, runs one PLC cycle and returns the points the
/// station handed to the analysis.
analysis::PointCloud points_the_station_analyses(const std::string& scanner_section) {
  TempDir dir("springscan-calibration");
  std::ofstream(dir.str() + "/part.step") << "ISO-10303-21;\n";  // must exist; never read here
  const std::string text =
      "modbus { bind_address: \"127.0.0.1\" port: 0 }\n" + scanner_section + "serial: \"" +
      kSerial + "\" timeout_s: 2 }\n" +
      "parts { part_id: 3 cad_file: \"part.step\" }\nreport_dir: \"reports\"\n";
  auto settings = parse_daemon_config(text, dir.str() + "/station.textproto");
  EXPECT_TRUE(settings.ok()) << settings.message();
  if (!settings) return {};
  settings->station.runner.probe_interval_s = 0.05;
  auto scanner = drivers::make_scanner(settings->scanner);
  EXPECT_TRUE(scanner.ok()) << scanner.message();
  if (!scanner) return {};

  std::mutex mutex;
  analysis::PointCloud analysed;
  Log log(LogLevel::kError, nullptr, false);
  auto station = Station::create(
      settings->station, **scanner,
      [&](std::uint16_t, const analysis::PointCloud& scan) {
        std::lock_guard lock(mutex);
        analysed = scan;
        return testing::plane_analysis(scan, 1000.0);
      },
      log, [](const std::string&) {});
  EXPECT_TRUE(station.ok()) << station.message();
  if (!station) return {};
  std::atomic<bool> stop{false};
  std::thread loop([&] { (*station)->run(stop); });
  simulators::PlcClientSettings plc_settings;
  plc_settings.port = (*station)->port();
  plc_settings.step_timeout_s = 20.0;
  auto plc = simulators::PlcClient::connect(plc_settings);
  EXPECT_TRUE(plc.ok()) << plc.message();
  if (plc) {
    EXPECT_TRUE((*plc)
                    ->wait_for([](const auto& s) { return s.bit(regs::kDiScannerOnline); },
                               "SCANNER_ONLINE")
                    .ok());
    auto cycle = (*plc)->run_cycle(1, 3);
    EXPECT_TRUE(cycle.ok()) << cycle.message();
    if (cycle) {
      EXPECT_EQ(cycle->result.code, regs::ResultCode::kOk);
    }
  }
  stop = true;
  loop.join();
  std::lock_guard lock(mutex);
  return analysed;
}

void expect_moved_by(const analysis::PointCloud& analysed, const analysis::PointCloud& reference,
                     const analysis::Transform& T) {
  ASSERT_GT(reference.size(), 100u);
  ASSERT_EQ(analysed.size(), reference.size());
  double worst = 0.0;
  for (std::size_t i = 0; i < reference.size(); ++i)
    worst = std::max(worst, (analysed.points[i] - T * reference.points[i]).norm());
  EXPECT_LT(worst, 1e-6) << "largest distance from the hand-transformed point, mm";
  // Not trivially true: the motion moves the part by centimetres.
  EXPECT_GT((analysed.points[0] - reference.points[0]).norm(), 5.0);
}

drivers::LinkSettings link(std::uint16_t product_id) {
  drivers::LinkSettings l;
  l.usb.product_id = product_id;
  l.usb.serial = kSerial;
  l.data_timeout_ms = 2000;
  return l;
}

TEST(ScannerCalibration, LaserCalibrationFromTheConfigReachesTheAnalysedPoints) {
  auto emulator =
      simulators::EmulatedUsbScanner::create(device(ScannerKind::kLaserLine), hat_surface());
  ASSERT_TRUE(emulator.ok()) << emulator.message();
  drivers::LaserScannerSettings plain;  // the default calibration: the simulator's mount
  plain.link = link(drivers::protocol::kProductIdLaser);
  auto reference = drivers::LaserLineScanner(plain).scan(nullptr);
  ASSERT_TRUE(reference.ok()) << reference.message();
  const analysis::Transform T = calibration_motion();
  expect_moved_by(points_the_station_analyses(laser_section(T)), *reference, T);
}

TEST(ScannerCalibration, TactileTPartMachineFromTheConfigReachesTheAnalysedPoints) {
  auto emulator =
      simulators::EmulatedUsbScanner::create(device(ScannerKind::kTactileProbe), hat_surface());
  ASSERT_TRUE(emulator.ok()) << emulator.message();
  drivers::TactileScannerSettings plain;  // T_part_machine = identity
  plain.link = link(drivers::protocol::kProductIdTactile);
  auto reference = drivers::TactileProbeScanner(plain).scan(nullptr);
  ASSERT_TRUE(reference.ok()) << reference.message();
  const analysis::Transform T = calibration_motion();
  expect_moved_by(points_the_station_analyses(tactile_section(T)), *reference, T);
}

}  // namespace
}  // namespace springscan::daemon
