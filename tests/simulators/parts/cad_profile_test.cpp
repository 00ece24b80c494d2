#include "simulators/parts/cad_profile.hpp"

#include <gtest/gtest.h>

#include <numbers>

#include "tests/analysis/cad_test_util.hpp"

namespace springscan::analysis {
using namespace springscan::parts;  // test and demo parts (simulators/parts)
namespace {

using testing::TempDir;

double path_length(const ProfileSpec& spec) {
  double length = 0.0;
  for (const auto& element : profile_path(spec)) length += element.length_mm();
  return length;
}

TEST(CadProfile, ShellHasOneFacePerPathElement) {
  const ProfileSpec spec = hat_profile(20, 30, 40, 90, 4);
  const auto shape = make_profile_shape(spec);
  ASSERT_TRUE(shape) << shape.message();
  const auto& report = shape->report();
  EXPECT_EQ(report.faces, 9);
  EXPECT_EQ(report.shells, 1);
  EXPECT_EQ(report.solids, 0);
  // Open boundary: 9 edges at y = 0, 9 at y = width, the two end lines.
  EXPECT_EQ(report.free_edges, 20);
  EXPECT_NEAR(report.area_mm2, path_length(spec) * spec.width_mm, 1e-6);
}

TEST(CadProfile, SolidIsClosed) {
  ProfileSpec spec = z_profile(30, 40, 60, 5);
  spec.thickness_mm = 2.0;
  const auto shape = make_profile_shape(spec);
  ASSERT_TRUE(shape) << shape.message();
  const auto& report = shape->report();
  // 5 reference-side faces, 5 offset-side faces, 2 end faces, 2 side faces.
  EXPECT_EQ(report.faces, 14);
  EXPECT_EQ(report.solids, 1);
  EXPECT_EQ(report.free_edges, 0);
}

TEST(CadProfile, InvalidSpecIsAnError) {
  EXPECT_FALSE(make_profile_shape(ProfileSpec{}));
  TempDir dir;
  const auto written = write_profile_cad(ProfileSpec{}, dir.file("bad.step"));
  ASSERT_FALSE(written);
  EXPECT_NE(written.message().find("bad.step"), std::string::npos);
  EXPECT_FALSE(write_profile_cad(l_profile(40, 30, 90, 3), dir.file("part.obj")));
}

// Written as IGES and STEP and read back: the same faces and area (the reader's sewing joins the
// IGES faces into one shell again).
TEST(CadProfile, IgesAndStepRoundTrip) {
  TempDir dir;
  ProfileSpec spec = u_profile(25, 40, 90, 3);
  for (double thickness : {0.0, 1.5}) {
    spec.thickness_mm = thickness;
    const auto built = make_profile_shape(spec);
    ASSERT_TRUE(built) << built.message();
    for (const char* name : {"u.igs", "u.step", "u.brep"}) {
      ASSERT_TRUE(write_profile_cad(spec, dir.file(name)));
      const auto back = load_cad(dir.file(name));
      ASSERT_TRUE(back) << back.message();
      EXPECT_EQ(back->report().faces, built->report().faces) << name << " t=" << thickness;
      EXPECT_EQ(back->report().free_edges, built->report().free_edges) << name;
      EXPECT_NEAR(back->report().area_mm2, built->report().area_mm2,
                  1e-4 * built->report().area_mm2)
          << name;
    }
  }
}

}  // namespace
}  // namespace springscan::analysis
