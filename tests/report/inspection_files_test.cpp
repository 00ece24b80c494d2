// report.json / report.pb / deviation.ply: round trips, the .proto field names, the colour
// scale, and atomic writes that leave no temporary file behind.
#include "report/inspection_files.hpp"

#include <gtest/gtest.h>

#include <filesystem>

#include "analysis/io/point_io.hpp"

namespace springscan::analysis {
using namespace springscan::report;
namespace {

namespace fs = std::filesystem;

fs::path fresh_dir(const std::string& name) {
  const fs::path dir = fs::path(::testing::TempDir()) / name;
  fs::remove_all(dir);
  return dir;
}

std::vector<std::string> leftover_temporaries(const fs::path& dir) {
  std::vector<std::string> found;
  for (const auto& entry : fs::directory_iterator(dir)) {
    const std::string name = entry.path().filename().string();
    if (name.ends_with(".tmp")) found.push_back(name);
  }
  return found;
}

InspectionOutcome sample_outcome() {
  InspectionOutcome outcome;
  auto& r = outcome.report;
  r.set_schema("springscan.report.v1");
  for (int k = 0; k < 16; ++k) r.mutable_global_fit()->add_transform(k % 5 == 0 ? 1.0 : 0.0);
  r.mutable_global_fit()->set_rms_final(0.0421);
  r.mutable_global_fit()->add_error_history(2.5);
  r.mutable_global_fit()->add_error_history(0.25);
  r.mutable_deviation()->set_tolerance_mm(0.5);  // colour scale: 3 x 0.5 = 1.5 mm
  r.mutable_deviation()->set_p95(0.31);
  auto* bend = r.add_bends();
  bend->set_nominal_angle_deg(90.0);
  bend->set_measured_angle_deg(88.5);
  bend->set_springback_deg(1.5);
  r.mutable_verdict()->add_reasons("bend 0: springback 1.5 deg > 1 deg");
  r.mutable_timings_ms()->set_total(123.5);
  r.set_job_id(9007199254740993);  // 2^53 + 1: int64 survives JSON as a string
  for (int i = 0; i < 61; ++i) {
    outcome.deviation_cloud.points.emplace_back(i, 0.5 * i, -i);
    outcome.deviation_cloud.scalars.push_back(-3.0 + 0.1 * i);
  }
  return outcome;
}

TEST(ReportFiles, ColourScaleComesFromTheReport) {
  v1::InspectionReport report;
  EXPECT_EQ(deviation_color_scale_mm(report), 1.0);
  report.mutable_deviation()->set_tolerance_mm(0.2);
  EXPECT_DOUBLE_EQ(deviation_color_scale_mm(report), 0.6);
  report.mutable_deviation()->set_color_scale_mm(2.0);
  EXPECT_EQ(deviation_color_scale_mm(report), 2.0);
}

TEST(ReportFiles, RoundTripAllFiles) {
  const fs::path dir = fresh_dir("springscan_report_files") / "nested";
  const InspectionOutcome outcome = sample_outcome();
  auto written = write_inspection_files(dir.string(), outcome);
  ASSERT_TRUE(written) << written.message();
  EXPECT_EQ(written->html_error, "");
  EXPECT_TRUE(fs::exists(dir / "report.html"));
  EXPECT_TRUE(leftover_temporaries(dir).empty());

  auto pb = read_report_pb((dir / "report.pb").string());
  ASSERT_TRUE(pb) << pb.message();
  EXPECT_EQ(pb->SerializeAsString(), outcome.report.SerializeAsString());

  auto json_text = read_file_bytes((dir / "report.json").string());
  ASSERT_TRUE(json_text);
  for (const char* field :
       {"\"global_fit\"", "\"rms_final\"", "\"timings_ms\"", "\"error_history\"",
        "\"springback_deg\"", "\"fraction_out_of_tolerance\"", "\"rms_after_pca\": 0",
        "\"job_id\": \"9007199254740993\""}) {
    EXPECT_NE(json_text->find(field), std::string::npos) << field;
  }
  EXPECT_EQ(json_text->find("rmsFinal"), std::string::npos);  // no lowerCamelCase names
  auto from_json = report_from_json(*json_text);
  ASSERT_TRUE(from_json) << from_json.message();
  EXPECT_EQ(from_json->SerializeAsString(), outcome.report.SerializeAsString());

  auto ply = read_point_cloud((dir / "deviation.ply").string());
  ASSERT_TRUE(ply) << ply.message();
  EXPECT_EQ(ply->points, outcome.deviation_cloud.points);
  EXPECT_EQ(ply->scalars, outcome.deviation_cloud.scalars);  // read back by its name
  ASSERT_EQ(ply->colors.size(), ply->size());
  for (std::size_t i = 0; i < ply->size(); ++i) {
    EXPECT_EQ(ply->colors[i], deviation_color(outcome.deviation_cloud.scalars[i], 1.5)) << i;
  }
  EXPECT_EQ(ply->colors.front(), (Rgb{0, 0, 255}));  // -3 mm: beyond -1.5, full blue
  EXPECT_EQ(ply->colors.back(), (Rgb{255, 0, 0}));   // +3 mm: full red
  EXPECT_EQ(ply->colors[30], (Rgb{0, 255, 0}));      // 0 mm: green

  // Writing again replaces the files in place.
  InspectionOutcome second = outcome;
  second.report.mutable_global_fit()->set_rms_final(0.5);
  ASSERT_TRUE(write_inspection_files(dir.string(), second));
  EXPECT_EQ(read_report_pb((dir / "report.pb").string())->global_fit().rms_final(), 0.5);
  EXPECT_TRUE(leftover_temporaries(dir).empty());
  fs::remove_all(dir.parent_path());
}

// report.json carries the shape figures under their proto names; a flat flange has no curl.
TEST(ReportFiles, JsonCarriesTheShapeFigures) {
  v1::InspectionReport r = sample_outcome().report;
  auto* station = r.mutable_bends(0)->add_angle_along_bend();
  station->set_position_mm(-20.0);
  station->set_angle_deg(88.25);
  r.mutable_bends(0)->set_angle_spread_deg(0.5);
  r.mutable_bends(0)->set_measured_radius_mm(4.03);
  auto* curled = r.add_segments();
  curled->set_shape_measured(true);
  curled->set_flatness_mm(1.5);
  curled->set_curl_radius_mm(-240.0);
  curled->set_twist_deg_per_100mm(0.25);
  auto* flat = r.add_segments();
  flat->set_id(1);
  flat->set_shape_measured(true);
  const auto json = report_to_json(r);
  ASSERT_TRUE(json) << json.message();
  for (const char* field :
       {"\"angle_along_bend\"", "\"position_mm\": -20", "\"angle_deg\": 88.25",
        "\"angle_spread_deg\": 0.5", "\"measured_radius_mm\": 4.03", "\"flatness_mm\": 1.5",
        "\"curl_radius_mm\": -240", "\"twist_deg_per_100mm\": 0.25", "\"end_tangents\": false"})
    EXPECT_NE(json->find(field), std::string::npos) << field;
  EXPECT_EQ(json->find("\"curl_radius_mm\""), json->rfind("\"curl_radius_mm\"")) << "flat: absent";
  const auto back = report_from_json(*json);
  ASSERT_TRUE(back) << back.message();
  EXPECT_TRUE(back->segments(0).has_curl_radius_mm());
  EXPECT_FALSE(back->segments(1).has_curl_radius_mm());
}

TEST(ReportFiles, ErrorsNameTheFile) {
  const fs::path dir = fresh_dir("springscan_report_errors");
  fs::create_directories(dir);
  auto missing = read_report_pb((dir / "none.pb").string());
  ASSERT_FALSE(missing);
  EXPECT_NE(missing.message().find("none.pb"), std::string::npos);
  ASSERT_TRUE(write_file_atomically((dir / "bad.pb").string(), "\xff\xff\xff garbage"));
  auto bad = read_report_pb((dir / "bad.pb").string());
  ASSERT_FALSE(bad);
  EXPECT_NE(bad.message().find("bad.pb"), std::string::npos) << bad.message();
  // A regular file where the directory should be.
  ASSERT_TRUE(write_file_atomically((dir / "file").string(), "x"));
  EXPECT_FALSE(write_inspection_files((dir / "file").string(), sample_outcome()));
  fs::remove_all(dir);
}

TEST(WriteFileAtomically, ReplacesContentAndCleansUp) {
  const fs::path dir = fresh_dir("springscan_atomic");
  fs::create_directories(dir);
  const std::string path = (dir / "data.bin").string();
  ASSERT_TRUE(write_file_atomically(path, "first version, longer"));
  ASSERT_TRUE(write_file_atomically(path, std::string("second\0v", 8)));
  EXPECT_EQ(read_file_bytes(path).value(), std::string("second\0v", 8));
  ASSERT_TRUE(write_file_atomically(path, ""));
  EXPECT_EQ(read_file_bytes(path).value(), "");
  EXPECT_TRUE(leftover_temporaries(dir).empty());
  auto error = write_file_atomically((dir / "no_such_dir" / "x.bin").string(), "x");
  ASSERT_FALSE(error);
  EXPECT_NE(error.message().find("no_such_dir"), std::string::npos) << error.message();
  EXPECT_TRUE(leftover_temporaries(dir).empty());
  fs::remove_all(dir);
}

// The compensation files a tool designer loads, written with the others.
TEST(ReportFiles, CompensationFilesAndTheCompensatedSurface) {
  InspectionOutcome outcome = sample_outcome();
  CompensationVector c;
  c.point = Vec3(1.0, 2.0, 3.0);
  c.vector = Vec3(0.0, 0.0, -0.25);
  c.supported = true;
  outcome.compensation.vectors.push_back(c);
  outcome.compensated_surface.vertices = {{0, 0, 0.1}, {1, 0, 0.1}, {0, 1, 0.1}};
  outcome.compensated_surface.triangles = {{0, 1, 2}};
  const fs::path dir = fresh_dir("compensation_files");
  ASSERT_TRUE(write_inspection_files(dir.string(), outcome));
  const auto csv = read_file_bytes((dir / "compensation.csv").string());
  ASSERT_TRUE(csv);
  EXPECT_EQ(*csv,
            "x_mm,y_mm,z_mm,cx_mm,cy_mm,cz_mm,magnitude_mm,supported,clipped\n"
            "1.000000,2.000000,3.000000,0.000000,0.000000,-0.250000,0.250000,1,0\n");
  const auto ply = read_file_bytes((dir / "compensation.ply").string());
  ASSERT_TRUE(ply);
  EXPECT_NE(ply->find("element vertex 1"), std::string::npos);
  auto stl = read_surface((dir / "compensated-surface.stl").string());
  ASSERT_TRUE(stl) << stl.message();
  ASSERT_EQ(stl->triangles.size(), 1u);
  for (const Vec3& p : stl->cloud.points) EXPECT_NEAR(p.z(), 0.1, 1e-6);
  EXPECT_TRUE(leftover_temporaries(dir).empty());
}

}  // namespace
}  // namespace springscan::analysis
