// Hardware in the loop with a GenICam profiler (issue 33): springscand configured with
// `scanner { genicam { } }` drives the simulated profiler (simulators/genicam_camera.hpp),
// hosted in this test process and reached over real GigE Vision on 127.0.0.1, while the
// simulated PLC runs the handshake. The profiler scans the demo hat as produced with a known
// springback (simulators/parts/laser_scan.hpp); the verdict and the springback must come out
// as for the USB head (hil_test.cpp), and a profiler that vanishes mid-scan must take the USB
// unplug's path (hil_fault_test.cpp) with the station serving again once it is back.
#include <cmath>
#include <csignal>
#include <set>
#include <sstream>

#include "analysis/io/point_io.hpp"
#include "hil_rig.hpp"
#include "simulators/genicam_camera.hpp"
#include "simulators/parts/produced_part.hpp"

namespace springscan::daemon {
namespace {

// Per bend as the CAD file numbers them (Bend::id, what the profiler simulator takes), each its
// own, within the demo's 1 degree tolerance.
const std::vector<double> kSpringback{0.3, 0.7, 0.5, 0.2};
constexpr double kBoundDeg = 0.05;  // as the USB head's HIL test (hil_test.cpp), sigma 0.02 mm
constexpr int kLinesPerFrame = 16;

/// The valid pixels of `image` outside the lines of lost frames `lost` (1-based frame numbers).
std::int64_t valid_pixels(const simulators::RangeImage& image, const std::set<int>& lost) {
  std::int64_t n = 0;
  for (int line = 0; line < image.lines; ++line) {
    if (lost.count(line / kLinesPerFrame + 1) != 0) continue;
    for (int i = 0; i < image.width; ++i)
      n += std::isnan(image.range_mm[std::size_t(line) * std::size_t(image.width) + i]) ? 0 : 1;
  }
  return n;
}

class GenicamHilTest : public testing::HilTest {
 protected:
  /// kSpringback in path order (HilTest::expect_springback's truth): each CAD bend placed on the
  /// hat's profile by its axis.
  static std::vector<double> truth_in_path_order() {
    auto cad = parts::load_cad_part(springscan::test_paths::source("demo/hat-profile.step"));
    if (!cad) {
      ADD_FAILURE() << cad.message();
      return {};
    }
    std::vector<double> truth(kSpringback.size(), NAN);
    for (const auto& b : cad->model.segmentation.bends) {
      v1::Bend bend;
      bend.mutable_axis_point()->set_x(b.axis_point.x());
      bend.mutable_axis_point()->set_y(b.axis_point.y());
      bend.mutable_axis_point()->set_z(b.axis_point.z());
      const int i = path_index(bend);
      if (i < 0 || b.id < 0 || std::size_t(b.id) >= kSpringback.size()) {
        ADD_FAILURE() << "CAD bend " << b.id << " is at no bend of the hat's profile";
        return {};
      }
      truth[std::size_t(i)] = kSpringback[std::size_t(b.id)];
    }
    return truth;
  }

  /// Starts the profiler scanning the hat and writes the daemon's config for it.
  void start_camera(simulators::GenicamCameraSettings camera = {}) {
    parts::LaserScanSettings scan;
    scan.line_spacing_mm = 1.0;  // 1 mm between lines, 1 mm between points: ~11000 points
    scan.noise_sigma_mm = 0.02;
    auto image = simulators::part_range_image(
        springscan::test_paths::source("demo/hat-profile.step"), kSpringback, scan, 200.0);
    ASSERT_TRUE(image) << image.message();
    camera.frame_period_us = 2000;
    auto started = simulators::GenicamCamera::start(camera, std::move(*image));
    ASSERT_TRUE(started) << started.message();
    camera_ = std::move(*started);
    write_genicam_config(camera_->image());
  }

  // As HilTest::write_config, with the profiler for a scanner. The motion origin is where the
  // simulated part's first line lies (a station measures it when it calibrates the head).
  void write_genicam_config(const simulators::RangeImage& image,
                            const std::string& motion = "") const {
    std::ofstream(config_path())
        << "modbus { bind_address: \"127.0.0.1\" port: 0 allowed_clients: \"127.0.0.1\" }\n"
        << "scanner { timeout_s: 1\n"
        << "  laser_calibration { origin_mm { x: 0 y: " << image.y0_mm << " z: 200 } }\n"
        << "  genicam { camera_id: \"127.0.0.1\" "
        << (motion.empty() ? "line_step_mm: " + std::to_string(image.dy_mm) : motion)
        << " scan_lines: " << image.lines << " lines_per_frame: " << kLinesPerFrame
        << " max_lost_frames: " << max_lost_frames_ << " } }\n"
        << "parts { part_id: 1 name: \"demo hat profile\" cad_file: \""
        << springscan::test_paths::source("demo/hat-profile.step")
        << "\"\n  settings { verdict { tolerance_mm: 0.5 angle_tolerance_deg: 1 } } }\n"
        << "report_dir: \"" << reports() << "\"\nmodel_cache_dir: \"" << dir_.str()
        << "/model-cache\"\nlog_level: \"warning\"\n";
  }

  std::unique_ptr<testing::DaemonProcess> start_genicam_daemon(
      const std::string& log_path = "") const {
    return std::make_unique<testing::DaemonProcess>(springscan::test_paths::kSpringscand,
                                                    config_path(), dir_.str(),
                                                    std::vector<std::string>{}, 60.0, log_path);
  }

  std::unique_ptr<simulators::GenicamCamera> camera_;
  int max_lost_frames_ = 0;  // scanner.genicam.max_lost_frames in the config written
};

TEST_F(GenicamHilTest, TriggerToVerdictThroughGigEVision) {
  start_camera();
  auto daemon = start_genicam_daemon();
  auto client = plc(daemon->port());
  wait_online(*client);
  auto cycle = client->run_cycle(1, 1);
  ASSERT_TRUE(cycle.ok()) << cycle.message();
  EXPECT_EQ(cycle->result.code, regs::ResultCode::kOk);
  EXPECT_TRUE(cycle->part_ok);
  const v1::InspectionReport r = report(1);
  expect_springback(r, truth_in_path_order(), kBoundDeg);
  EXPECT_EQ(r.input().scan_points(), valid_pixels(camera_->image(), {}));
  expect_registers_match(cycle->result, r);
  EXPECT_EQ(camera_->scans_started(), 1);
  EXPECT_EQ(daemon->stop(SIGTERM), 0);
}

// `springscan scan --genicam ID` writes the profiler's scan: every valid pixel, in place.
TEST_F(GenicamHilTest, CliScanWritesThePly) {
  simulators::RangeImage image;
  image.width = 20;
  image.lines = 32;
  image.x0_mm = -5.0;
  image.dx_mm = 0.5;
  for (int k = 0; k < image.width * image.lines; ++k)
    image.range_mm.push_back(k % 5 == 0 ? NAN : float(100.0 + 0.01 * k));
  auto camera = simulators::GenicamCamera::start({}, image);
  ASSERT_TRUE(camera) << camera.message();
  const std::string out = dir_.str() + "/genicam.ply";
  const auto [status, output] =
      testing::run_command(std::string(springscan::test_paths::kSpringscan) +
                           " scan --genicam 127.0.0.1 --line-step 0.25 --lines 32 --out " + out);
  ASSERT_EQ(status, 0) << output;
  auto cloud = analysis::read_point_cloud(out);
  ASSERT_TRUE(cloud) << cloud.message();
  ASSERT_EQ(cloud->size(), std::size_t(image.width * image.lines * 4 / 5));
  for (const auto& p : cloud->points) {  // default head: 200 mm above, moving along +y
    const int i = static_cast<int>(std::lround((p.x() + 5.0) / 0.5));
    const int line = static_cast<int>(std::lround(p.y() / 0.25));
    const int k = line * image.width + i;
    ASSERT_TRUE(i >= 0 && i < image.width && line >= 0 && line < image.lines && k % 5 != 0);
    ASSERT_NEAR(p.z(), 200.0 - (100.0 + 0.01 * k), 0.0021);
  }
}

// springscand --check opens the camera: present and complete, absent, lacking a feature.
TEST_F(GenicamHilTest, CheckReportsAnAbsentCameraAndAMissingFeatureByName) {
  const std::string check =
      std::string(springscan::test_paths::kSpringscand) + " --check --config " + config_path();
  simulators::RangeImage image;
  image.width = 10;
  image.lines = 4;
  image.range_mm.assign(40, 150.0f);
  write_genicam_config(image);
  const auto [absent_status, absent] = testing::run_command(check);
  EXPECT_NE(absent_status, 0);
  EXPECT_NE(absent.find("genicam camera '127.0.0.1': not found"), std::string::npos) << absent;

  std::ifstream in(simulators::default_genicam_xml());
  std::stringstream xml;
  xml << in.rdbuf();
  std::string text = xml.str();
  const std::string line_rate = "Name=\"AcquisitionLineRate\"";  // speed_mm_s needs it
  text.replace(text.find(line_rate), line_rate.size(), "Name=\"LineRateRenamed\"");
  const std::string path = dir_.str() + "/no-line-rate.xml";
  std::ofstream(path) << text;
  simulators::GenicamCameraSettings settings;
  settings.genicam_xml = path;
  auto camera = simulators::GenicamCamera::start(settings, image);
  ASSERT_TRUE(camera) << camera.message();
  write_genicam_config(image, "speed_mm_s: 100");  // the line rate from the camera
  const auto [missing_status, missing] = testing::run_command(check);
  EXPECT_NE(missing_status, 0);
  EXPECT_NE(missing.find("lacks the GenICam feature(s) AcquisitionLineRate"), std::string::npos)
      << missing;

  write_genicam_config(image);
  const auto [ok_status, ok] = testing::run_command(check);
  EXPECT_EQ(ok_status, 0) << ok;
}

TEST_F(GenicamHilTest, CameraGoneMidScanIsTheUnplugPathAndTheStationServesAgain) {
  simulators::GenicamCameraSettings camera;
  camera.vanish_after_lines = 32;  // two of the five frames, then no answer
  start_camera(camera);
  auto daemon = start_genicam_daemon();
  auto client = plc(daemon->port());
  wait_online(*client);
  auto failed = client->run_cycle(1, 1, false);
  ASSERT_TRUE(failed.ok()) << failed.message();
  EXPECT_EQ(failed->result.code, regs::ResultCode::kScanFailed);
  EXPECT_FALSE(failed->part_ok);
  EXPECT_EQ(failed->error_code, static_cast<std::uint16_t>(regs::ErrorCode::kScanFailed));
  auto status = client->read_status();
  ASSERT_TRUE(status.ok());
  EXPECT_EQ(status->live[regs::kIrState], static_cast<std::uint16_t>(regs::State::kFault));
  EXPECT_EQ(status->live[regs::kIrErrorDetail],
            static_cast<std::uint16_t>(regs::ErrorDetail::kDeviceGone));
  const v1::InspectionReport scan_failed = report(1);
  ASSERT_GE(scan_failed.verdict().reasons_size(), 1);
  EXPECT_NE(scan_failed.verdict().reasons(0).find("scan failed"), std::string::npos);
  wait_online(*client, false);  // the daemon closed it and does not find it
  ASSERT_TRUE(client->acknowledge().ok());

  // The camera is back; the daemon reopens it, and after ERROR_RESET the next part passes.
  camera_->bring_back();
  wait_online(*client);
  ASSERT_TRUE(client->reset_errors().ok());
  auto next = client->run_cycle(2, 1);
  ASSERT_TRUE(next.ok()) << next.message();
  EXPECT_EQ(next->result.seq, 2);
  EXPECT_EQ(next->result.code, regs::ResultCode::kOk);
  expect_springback(report(2), truth_in_path_order(), kBoundDeg);
  EXPECT_EQ(record_count(), 2);  // the failed scan's record is kept
  EXPECT_EQ(daemon->stop(SIGTERM), 0);
}

// Frames lost on the wire (the profiler skips a block id: what a congested link does), within
// max_lost_frames: their lines have no points, the rest measures the part as before, and the
// log says what was lost and where to look.
TEST_F(GenicamHilTest, FramesLostWithinTheLimitLeaveTheirLinesOutAndAreLogged) {
  simulators::GenicamCameraSettings camera;
  camera.lose_every_nth_frame = 4;  // the 4th frame of the pass (lines 48-63) never arrives
  // One more allowed: on a loaded machine Aravis may give up on a starved frame of its own.
  max_lost_frames_ = 2;
  start_camera(camera);
  ASSERT_LT(camera_->image().lines, 8 * kLinesPerFrame) << "one lost frame per pass expected";
  const std::string log = dir_.str() + "/springscand.log";
  auto daemon = start_genicam_daemon(log);
  auto client = plc(daemon->port());
  wait_online(*client);
  auto cycle = client->run_cycle(1, 1);
  ASSERT_TRUE(cycle.ok()) << cycle.message();
  EXPECT_EQ(cycle->result.code, regs::ResultCode::kOk);
  EXPECT_EQ(camera_->frames_lost(), 1);
  const v1::InspectionReport r = report(1);
  // Frame 4's lines are missing (and at most one more frame's, lost on a loaded machine).
  const std::int64_t without_4 = valid_pixels(camera_->image(), {4});
  EXPECT_LE(r.input().scan_points(), without_4);
  EXPECT_GE(r.input().scan_points(), without_4 - kLinesPerFrame * camera_->image().width);
  expect_springback(r, truth_in_path_order(), kBoundDeg);
  EXPECT_EQ(daemon->stop(SIGTERM), 0);
  std::stringstream text;
  text << std::ifstream(log).rdbuf();
  EXPECT_NE(text.str().find("frames lost on the network"), std::string::npos) << text.str();
}

// Beyond max_lost_frames the scan fails as a corrupt USB frame sequence does (SEQUENCE_GAP):
// no verdict from a scan with holes, the record kept; once the link is clean the station
// measures again after ERROR_RESET.
TEST_F(GenicamHilTest, FramesLostBeyondTheLimitFailTheScanAndACleanLinkMeasuresAgain) {
  simulators::GenicamCameraSettings camera;
  camera.lose_every_nth_frame = 2;
  start_camera(camera);
  auto daemon = start_genicam_daemon();
  auto client = plc(daemon->port());
  wait_online(*client);
  auto failed = client->run_cycle(1, 1, false);
  ASSERT_TRUE(failed.ok()) << failed.message();
  EXPECT_EQ(failed->result.code, regs::ResultCode::kScanFailed);
  EXPECT_FALSE(failed->part_ok);
  auto status = client->read_status();
  ASSERT_TRUE(status.ok());
  EXPECT_EQ(status->live[regs::kIrErrorDetail],
            static_cast<std::uint16_t>(regs::ErrorDetail::kSequenceGap));
  const v1::InspectionReport scan_failed = report(1);
  ASSERT_GE(scan_failed.verdict().reasons_size(), 1);
  EXPECT_NE(scan_failed.verdict().reasons(0).find("lines lost (max_lost_frames 0)"),
            std::string::npos)
      << scan_failed.verdict().reasons(0);
  ASSERT_TRUE(client->acknowledge().ok());

  camera_->set_frame_loss(0);
  ASSERT_TRUE(client->reset_errors().ok());
  auto next = client->run_cycle(2, 1);
  ASSERT_TRUE(next.ok()) << next.message();
  EXPECT_EQ(next->result.code, regs::ResultCode::kOk);
  expect_springback(report(2), truth_in_path_order(), kBoundDeg);
  EXPECT_EQ(record_count(), 2);
  EXPECT_EQ(daemon->stop(SIGTERM), 0);
}

}  // namespace
}  // namespace springscan::daemon
