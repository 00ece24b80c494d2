#include "analysis/cad/import.hpp"

#include <gtest/gtest.h>

#include <cctype>
#include <fstream>

#include "simulators/parts/cad_profile.hpp"
#include "tests/analysis/cad_test_util.hpp"

namespace springscan::analysis {
using namespace springscan::parts;  // test and demo parts (simulators/parts)
namespace {

using testing::shared_cad;
using testing::TempDir;

void write_text(const std::string& path, const std::string& text) { std::ofstream(path) << text; }

TEST(CadImport, ErrorsNameTheFileAndWhatFailed) {
  TempDir dir;
  const auto missing = load_cad(dir.file("missing.step"));
  ASSERT_FALSE(missing);
  EXPECT_NE(missing.message().find("missing.step: no such file"), std::string::npos);
  EXPECT_TRUE(missing.error().is_not_found()) << missing.error().to_string();

  write_text(dir.file("empty.igs"), "");
  const auto empty = load_cad(dir.file("empty.igs"));
  ASSERT_FALSE(empty);
  EXPECT_NE(empty.message().find("empty.igs: the file is empty"), std::string::npos);
  EXPECT_TRUE(empty.error().is_corruption()) << empty.error().to_string();

  write_text(dir.file("part.stl"), "solid x\nendsolid x\n");
  const auto stl = load_cad(dir.file("part.stl"));
  ASSERT_FALSE(stl);
  EXPECT_NE(stl.message().find("part.stl: unsupported file type"), std::string::npos);
  EXPECT_TRUE(stl.error().is_invalid_input()) << stl.error().to_string();

  write_text(dir.file("junk.step"), "this is not a STEP file\n");
  const auto junk = load_cad(dir.file("junk.step"));
  ASSERT_FALSE(junk);
  EXPECT_NE(junk.message().find("junk.step"), std::string::npos) << junk.message();
  EXPECT_TRUE(junk.error().is_corruption()) << junk.error().to_string();

  write_text(dir.file("junk.brep"), "garbage\n");
  const auto brep = load_cad(dir.file("junk.brep"));
  ASSERT_FALSE(brep);
  EXPECT_NE(brep.message().find("junk.brep"), std::string::npos) << brep.message();
}

// The real files: counts from SOURCES.md (measured with OCCT 7.6.3).
struct RealFile {
  const char* name;
  int faces;
  double area_mm2;
  Vec3 size_mm;
};

class CadImportRealFiles : public ::testing::TestWithParam<RealFile> {};

TEST_P(CadImportRealFiles, LoadInMillimetres) {
  const RealFile& file = GetParam();
  const auto shape = load_cad(shared_cad(file.name));
  ASSERT_TRUE(shape) << shape.message();
  const CadLoadReport& report = shape->report();
  std::cout << "[ cad ] " << file.name << ": " << summary(report) << "\n";
  EXPECT_EQ(report.faces, file.faces);
  const Vec3 size = report.bbox_max - report.bbox_min;
  // Bounding boxes include the shape tolerance: within 1 % (or 0.05 mm).
  for (int k = 0; k < 3; ++k)
    EXPECT_NEAR(size[k], file.size_mm[k], std::max(0.05, 0.01 * file.size_mm[k])) << k;
  EXPECT_NEAR(report.area_mm2, file.area_mm2, 1e-3 * file.area_mm2);
  EXPECT_EQ(report.faces_without_mesh, 0);
  EXPECT_GT(report.triangles, 0);
}

INSTANTIATE_TEST_SUITE_P(
    SharedData, CadImportRealFiles,
    ::testing::Values(RealFile{"bug3883_xr2-ct-214_l-bracket.stp", 16, 24628.319, {50, 60, 100}},
                      RealFile{"bug3883_xr2-ct-214_plate.stp", 18, 70027.433, {180, 150, 20}},
                      RealFile{"bug25169_box-openshell.stp", 6, 2400.0, {20, 20, 20}},
                      RealFile{"OCC8842_cylinder_CATIA.igs", 4, 47123.890, {100, 100, 100}},
                      RealFile{"nema-17-bracket.step", 42, 6221.984, {35, 41, 51}},
                      RealFile{"steel-sheets-2000mm.step", 62, 3875891.118, {840, 2000, 25}}),
    [](const auto& param_info) {
      std::string name = param_info.param.name;
      for (auto& c : name)
        if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
      return name;
    });

// bearing.iges declares millimetres but holds metres (a 0.1 mm bearing otherwise): the
// metre-scale rule brings it to 101 x 122 x 31 mm; its loose faces are sewn.
TEST(CadImport, MetreScaleIgesComesOutInMillimetres) {
  CadImportSettings coarse;  // 213 faces: a coarser mesh keeps the test fast
  coarse.linear_deflection_mm = 0.2;
  const auto shape = load_cad(shared_cad("bearing.iges"), coarse);
  ASSERT_TRUE(shape) << shape.message();
  const auto& report = shape->report();
  std::cout << "[ cad ] bearing.iges: " << summary(report) << "\n";
  EXPECT_EQ(report.scale_applied, 1000.0);
  EXPECT_TRUE(report.sewn);
  const Vec3 size = report.bbox_max - report.bbox_min;
  EXPECT_NEAR(size.x(), 101.0, 1.0);
  EXPECT_NEAR(size.y(), 122.0, 1.0);
  EXPECT_NEAR(size.z(), 31.4, 1.0);
  EXPECT_NEAR(report.area_mm2, 0.013 * 1e6, 0.001 * 1e6);
}

// A file that declares metres is converted to mm by the reader: the L profile written in metres
// comes back with its size in millimetres, from IGES and from STEP.
TEST(CadImport, DeclaredUnitsAreConvertedToMillimetres) {
  TempDir dir;
  const ProfileSpec spec = l_profile(40, 30, 90, 3);
  for (const char* name : {"l_metres.igs", "l_metres.step", "l_inch.step"}) {
    const std::string unit = std::string(name).find("inch") != std::string::npos ? "INCH" : "M";
    ASSERT_TRUE(write_profile_cad(spec, dir.file(name), unit));
    const auto shape = load_cad(dir.file(name));
    ASSERT_TRUE(shape) << shape.message();
    const Vec3 size = shape->report().bbox_max - shape->report().bbox_min;
    EXPECT_NEAR(size.x(), 43.0, 1e-3) << name;  // 40 + radius 3
    EXPECT_NEAR(size.y(), 60.0, 1e-3) << name;  // default width
    EXPECT_NEAR(size.z(), 33.0, 1e-3) << name;
    EXPECT_EQ(shape->report().scale_applied, 1.0) << name;
  }
}

TEST(CadImport, BrepTextRoundTripKeepsTheShape) {
  const auto shape = make_profile_shape(u_profile(20, 40, 90, 2));
  ASSERT_TRUE(shape) << shape.message();
  const auto text = cad_to_brep_text(*shape);
  ASSERT_FALSE(text.empty());
  const auto back = cad_from_brep_text(text, "u.brep");
  ASSERT_TRUE(back) << back.message();
  EXPECT_EQ(back->face_count(), shape->face_count());
  EXPECT_NEAR(back->report().area_mm2, shape->report().area_mm2, 1e-9);
  EXPECT_FALSE(cad_from_brep_text("nonsense", "bad.brep"));
  EXPECT_FALSE(cad_from_brep_text("", "empty.brep"));
}

TEST(CadImport, RejectsNonPositiveDeflection) {
  CadImportSettings settings;
  settings.linear_deflection_mm = 0.0;
  const auto shape = make_profile_shape(l_profile(40, 30, 90, 3), settings);
  ASSERT_FALSE(shape);
  EXPECT_NE(shape.message().find("deflection"), std::string::npos);
}

}  // namespace
}  // namespace springscan::analysis
