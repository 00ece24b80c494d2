// The GenICam section of the config to driver settings, and the features the driver requires
// (drivers/genicam/genicam_scanner.hpp, drivers/scanner_proto.hpp).
#include <google/protobuf/text_format.h>
#include <gtest/gtest.h>

#include <algorithm>

#include "drivers/scanner_proto.hpp"

namespace springscan::drivers::genicam {
namespace {

v1::ScannerConfig parse(const std::string& text) {
  v1::ScannerConfig c;
  EXPECT_TRUE(google::protobuf::TextFormat::ParseFromString(text, &c)) << text;
  return c;
}

bool contains(const std::vector<std::string>& v, const std::string& s) {
  return std::find(v.begin(), v.end(), s) != v.end();
}

TEST(GenicamSettings, FromConfig) {
  const auto s = genicam_settings_from_proto(parse(R"(
    timeout_s: 0.5
    laser_calibration { origin_mm { x: 1 y: 2 z: 300 } }
    genicam { camera_id: "127.0.0.1" pixel_format: "Coord3D_ABC32f" scan_lines: 81
              lines_per_frame: 4 line_step_mm: 1.0 max_lost_frames: 2
              features { name: "ExposureTime" value: "50" } })"));
  ASSERT_TRUE(s) << s.message();
  EXPECT_EQ(s->camera_id, "127.0.0.1");
  EXPECT_EQ(s->pixel_format, RangeFormat::kCoord3dAbc32f);
  EXPECT_EQ(s->scan_lines, 81);
  EXPECT_EQ(s->lines_per_frame, 4);
  EXPECT_EQ(s->max_lost_frames, 2);
  EXPECT_EQ(s->frame_timeout_ms, 500);
  EXPECT_EQ(s->calibration.origin_mm, analysis::Vec3(1, 2, 300));
  ASSERT_EQ(s->features.size(), 1u);
  EXPECT_EQ(s->features[0].first, "ExposureTime");
  // The section alone chooses the driver, and check_scanner_config accepts it.
  EXPECT_TRUE(check_scanner_config(parse("genicam { line_step_mm: 0.5 }")));
}

TEST(GenicamSettings, BadFieldsAreNamed) {
  const auto bad_format =
      genicam_settings_from_proto(parse("genicam { pixel_format: \"Mono8\" line_step_mm: 1 }"));
  ASSERT_FALSE(bad_format);
  EXPECT_NE(bad_format.message().find("pixel_format = 'Mono8'"), std::string::npos);
  const auto no_motion = check_scanner_config(parse("genicam { camera_id: \"x\" }"));
  ASSERT_FALSE(no_motion);
  EXPECT_NE(no_motion.message().find("line_step_mm"), std::string::npos);
  const auto tactile =
      check_scanner_config(parse("kind: TACTILE_PROBE genicam { line_step_mm: 1 }"));
  ASSERT_FALSE(tactile);
  EXPECT_EQ(tactile.code(), analysis::ErrorCode::kInvalidSettings);
  EXPECT_FALSE(check_scanner_config(parse("genicam { line_step_mm: 1 lines_per_frame: 0 }")));
}

TEST(GenicamSettings, RequiredFeaturesFollowTheSettings) {
  GenicamSettings s;
  s.line_step_mm = 1.0;
  auto names = required_features(s);
  for (const char* n : {"Width", "Height", "PixelFormat", "Scan3dCoordinateSelector",
                        "Scan3dCoordinateScale", "Scan3dCoordinateOffset", "AcquisitionStart"})
    EXPECT_TRUE(contains(names, n)) << n;
  EXPECT_FALSE(contains(names, "AcquisitionLineRate"));  // an encoder gives the motion
  EXPECT_FALSE(contains(names, "Scan3dOutputMode"));
  s.line_step_mm = 0.0;
  s.speed_mm_s = 100.0;
  s.output_mode = "CalibratedABC_Grid";
  s.features = {{"ExposureTime", "40"}};
  names = required_features(s);
  EXPECT_TRUE(contains(names, "AcquisitionLineRate"));  // the line rate comes from the camera
  EXPECT_TRUE(contains(names, "Scan3dOutputMode"));
  EXPECT_TRUE(contains(names, "ExposureTime"));
}

TEST(GenicamScanner, AbsentCameraIsNotFoundAndOffline) {
  GenicamSettings s;
  s.camera_id = "springscan-no-such-camera";
  s.line_step_mm = 1.0;
  GenicamScanner scanner(s);
  const auto info = scanner.identify();
  ASSERT_FALSE(info);
  EXPECT_EQ(info.code(), analysis::ErrorCode::kNotFound);
  EXPECT_NE(info.message().find("springscan-no-such-camera"), std::string::npos);
  EXPECT_FALSE(scanner.online());
  const auto scan = scanner.scan({});
  ASSERT_FALSE(scan);
  EXPECT_EQ(scan.code(), analysis::ErrorCode::kNotFound);  // the daemon's "device gone" detail
}

}  // namespace
}  // namespace springscan::drivers::genicam
