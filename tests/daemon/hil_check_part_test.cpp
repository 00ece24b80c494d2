// Hardware in the loop, the check part (docs/calibration.md, issue 42): springscand with a
// check_part { } in its config, a two-head line scanner whose second head turns on its mount
// by 0.2 degree, and the PLC's view of CALIBRATION_DRIFT (discrete input 11): not raised by the
// unchanged station, raised by the drifted head, latched (over a restart too), and cleared by
// the next check part that passes (the head recalibrated).
//
// Why the springback of a two-head scan: a rigid turn of one head that sees the whole part
// moves the whole scan, and the best fit takes it back (report/check_part.hpp). Two heads that
// disagree bend the merged scan instead: a flange's fit turns with the share of it the drifted
// head sees, so the bends between flanges the heads see differently open or close by part of
// the drift, which no rigid fit can take back.
#include <signal.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <string>
#include <thread>

#include "hil_rig.hpp"

namespace springscan::daemon {
namespace {

using testing::HilTest;

// The check part: the demo hat made with the same springback at every bend, so each bend's
// reference holds however the fit labels the mirror-symmetric hat (hil_rig.hpp).
constexpr double kCheckSpringbackDeg = 0.4;
constexpr int kBends = 4;
// Half of what the drift moves a bend between the heads (0.1 degree), ten times the unchanged
// station's offset (0.004 degree on the simulator).
constexpr double kLimitDeg = 0.05;
constexpr double kHeadTiltDeg = 30.0;  // two heads at +-30 degree, each sees the walls facing it
constexpr double kDriftDeg = 0.2;      // the second head's turn on its mount

class HilCheckPartTest : public HilTest {
 protected:
  HilCheckPartTest() {
    std::ofstream config(config_path(), std::ios::app);
    config << "check_part { part_id: 1\n";
    for (int bend = 0; bend < kBends; ++bend) {  // the CAD segmentation numbers them from 0
      config << "  reference { characteristic: \"bend " << bend
             << " springback\" value: " << kCheckSpringbackDeg << " limit: " << kLimitDeg << " }\n";
    }
    config << "}\n";
  }

  /// The rig's emulated scanner (hil_rig.hpp emulate) with two heads, as calibrated.
  void emulate_two_heads() {
    simulators::ScannerDeviceSettings s;
    s.noise.sigma_mm = 0.02;
    s.laser.step_mm = 1.0;
    s.laser.points_per_profile = 200;
    s.laser.head_tilt_deg = kHeadTiltDeg;
    s.config.points_per_profile = 200;
    s.scan_duration_s = 0.4;
    parts::ScanSimulationSettings dense;
    dense.point_count = 150000;
    dense.noise_sigma_mm = 0.0;
    auto surface = parts::simulate_scan(parts::demo_hat_profile(),
                                        std::vector<double>(kBends, kCheckSpringbackDeg), dense);
    ASSERT_TRUE(surface.ok()) << surface.message();
    laser_ = s.laser;
    auto emulator = simulators::EmulatedUsbScanner::create(s, std::move(*surface));
    ASSERT_TRUE(emulator.ok()) << emulator.message();
    emulator_ = std::move(*emulator);
  }
  /// Turns the second head on its mount by `drift_deg` from the calibrated one (0: back).
  void drift_second_head(double drift_deg) {
    simulators::LaserPatternSettings laser = laser_;
    laser.second_head_drift_deg = drift_deg;
    emulator_->set_laser_pattern(laser);
  }

  /// One check part cycle (job `job`); returns CALIBRATION_DRIFT as the PLC reads it after.
  bool check_cycle(simulators::PlcClient& plc, std::uint16_t job) {
    auto cycle = plc.run_cycle(job, 1);
    EXPECT_TRUE(cycle.ok()) << cycle.message();
    if (!cycle.ok()) return false;
    EXPECT_TRUE(cycle->accepted);
    auto status = plc.read_status();
    EXPECT_TRUE(status.ok()) << status.message();
    if (!status.ok()) return false;
    const bool bit = status->bit(regs::kDiCalibrationDrift);
    // The status word mirrors the discrete inputs (PLCs that read registers only).
    EXPECT_EQ((status->live[regs::kIrStatusWord] >> regs::kDiCalibrationDrift) & 1u, bit ? 1u : 0u);
    return bit;
  }

  simulators::LaserPatternSettings laser_;
};

/// The largest |measured - reference| of a check whose references were all measured.
double largest_offset(const v1::CheckResult& check) {
  double largest = 0.0;
  EXPECT_EQ(check.items_size(), kBends);
  for (const v1::CheckItem& item : check.items()) {
    EXPECT_TRUE(item.has_measured()) << item.characteristic();
    largest = std::max(largest, std::abs(item.measured() - item.reference()));
  }
  return largest;
}

TEST_F(HilCheckPartTest, AHeadDriftingAFifthOfADegreeIsCaughtAndAnUnchangedStationIsNot) {
  emulate_two_heads();
  auto daemon = start_daemon();
  auto client = plc(daemon->port());
  wait_online(*client);

  // The station as calibrated: every bend within its limit, no alarm.
  EXPECT_FALSE(check_cycle(*client, 1));
  const v1::InspectionReport unchanged = report(1);
  ASSERT_TRUE(unchanged.has_check());
  EXPECT_FALSE(unchanged.check().drift());
  const double unchanged_offset = largest_offset(unchanged.check());
  EXPECT_LT(unchanged_offset, kLimitDeg);

  // The second head turns by 0.2 degree: the check part catches it.
  drift_second_head(kDriftDeg);
  EXPECT_TRUE(check_cycle(*client, 2));
  const v1::InspectionReport drifted = report(2);
  ASSERT_TRUE(drifted.has_check());
  EXPECT_TRUE(drifted.check().drift());
  // The springback moved by the drift injected. Each flange's fit mixes what the two heads see
  // of it, so it turns by between 0 (the first head's view) and the drift (the second's): a
  // bend changes by at most the drift, and the bends between flanges the heads see differently
  // change by a share of it, against the same bends as calibrated (the part's own error
  // cancels). A flange both heads see alike now shows two sheets apart: its bend is not
  // measured, which counts as drift too.
  std::string moved;
  int caught = 0;
  for (int i = 0; i < kBends; ++i) {
    const v1::CheckItem& now = drifted.check().items(i);
    if (!now.has_measured()) {
      moved += " n/a";
      continue;
    }
    const double change = now.measured() - unchanged.check().items(i).measured();
    EXPECT_LE(std::abs(change), kDriftDeg + 0.02) << now.characteristic();
    caught += now.beyond() ? 1 : 0;
    char text[16];
    std::snprintf(text, sizeof text, " %+.3f", change);
    moved += text;
  }
  EXPECT_GE(caught, 1) << "the springback itself crossed no limit";
  // systemd's status line says it too (sent with the bit; read by the notify thread).
  bool status_line = false;
  for (int i = 0; i < 200 && !(status_line = daemon->notified("CALIBRATION DRIFT")); ++i)
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  EXPECT_TRUE(status_line);
  std::printf(
      "check part: unchanged station within %.3f deg of the references (limit %.2f); "
      "second head turned %.2f deg: springback per bend moved%s deg\n",
      unchanged_offset, kLimitDeg, kDriftDeg, moved.c_str());

  // Latched: a restart of the station keeps it.
  EXPECT_EQ(daemon->stop(SIGTERM), 0);
  daemon = start_daemon();
  client = plc(daemon->port());
  wait_online(*client);
  auto restarted = client->read_status();
  ASSERT_TRUE(restarted.ok()) << restarted.message();
  EXPECT_TRUE(restarted->bit(regs::kDiCalibrationDrift));

  // Recalibrated (the head as the calibration has it): the next check part clears the latch.
  drift_second_head(0.0);
  EXPECT_FALSE(check_cycle(*client, 3));
  EXPECT_FALSE(report(3).check().drift());
}

}  // namespace
}  // namespace springscan::daemon
