#include "analysis/cad/segmentation.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <numbers>

#include "simulators/parts/cad_profile.hpp"
#include "tests/analysis/cad_test_util.hpp"

namespace springscan::analysis {
using namespace springscan::parts;  // test and demo parts (simulators/parts)
namespace {

using testing::shared_cad;
using testing::TempDir;

void print(const std::string& name, const PartSegmentation& s) {
  std::cout << "[ segmentation ] " << name << ": " << s.flanges.size() << " flanges, "
            << s.bends.size() << " bends, " << s.other_faces.size() << " other faces\n";
  for (const auto& b : s.bends)
    std::cout << "  bend " << b.id << ": flanges " << b.flange_a << "-" << b.flange_b << ", angle "
              << b.nominal_angle_deg << " deg, inner radius " << b.radius_mm << " mm, axis ("
              << b.axis_point.transpose() << ") + t (" << b.axis_direction.transpose() << ")\n";
}

// The path line a flange lies on: the reference side, or the offset side of a solid.
int line_of(const std::vector<ProfileElement>& path, const Flange& flange) {
  int best = -1;
  double best_distance = 1e300;
  const Eigen::Vector2d p(flange.point.x(), flange.point.z());
  for (const auto& e : path) {
    if (e.kind != ProfileElement::Kind::kLine) continue;
    const Eigen::Vector2d d = (e.end - e.start).normalized();
    const Eigen::Vector2d w = p - e.start;
    const double along = w.dot(d);
    if (along < -1e-6 || along > (e.end - e.start).norm() + 1e-6) continue;
    const double distance = std::abs(w.x() * d.y() - w.y() * d.x());
    if (distance < best_distance) best_distance = distance, best = e.flange_index;
  }
  return best;
}

struct Case {
  const char* name;
  ProfileSpec spec;
};

ProfileSpec thick(ProfileSpec spec) {
  spec.thickness_mm = 1.5;
  return spec;
}

class CadSegmentationProfiles : public ::testing::TestWithParam<std::tuple<Case, const char*>> {};

// Bends found with the ProfileSpec's axes, radii and angles; each joins the flanges on either
// side of its arc.
TEST_P(CadSegmentationProfiles, BendsMatchTheSpec) {
  const auto& [c, format] = GetParam();
  TempDir dir;
  Expected<CadShape> shape = fail("not loaded");
  if (std::string(format) == "built") {
    shape = make_profile_shape(c.spec);
  } else {
    const std::string path = dir.file(std::string("part.") + format);
    ASSERT_TRUE(write_profile_cad(c.spec, path));
    shape = load_cad(path);
  }
  ASSERT_TRUE(shape) << shape.message();
  const PartSegmentation s = segment_cad(*shape);
  print(std::string(c.name) + " " + format, s);
  const auto path = profile_path(c.spec);
  const std::size_t n = c.spec.flange_lengths_mm.size();
  ASSERT_EQ(s.flanges.size(), n);
  ASSERT_EQ(s.bends.size(), n - 1);
  // Solids: the two end faces and two side faces are not flanges.
  EXPECT_EQ(s.other_faces.size(), c.spec.thickness_mm > 0 ? 4u : 0u);
  std::vector<int> line_of_flange;
  for (const auto& f : s.flanges) line_of_flange.push_back(line_of(path, f));
  for (const auto& e : path) {
    if (e.kind != ProfileElement::Kind::kArc) continue;
    const Bend* match = nullptr;
    for (const auto& b : s.bends)
      if (std::hypot(b.axis_point.x() - e.center.x(), b.axis_point.z() - e.center.y()) < 1e-6)
        match = &b;
    ASSERT_NE(match, nullptr) << "no bend about the axis of arc " << e.bend_index;
    EXPECT_NEAR((match->axis_direction - Vec3::UnitY()).norm(), 0.0, 1e-9);
    const double t = c.spec.thickness_mm;
    const double inner = e.sweep_rad > 0 || t == 0 ? e.radius_mm : e.radius_mm - t;
    EXPECT_NEAR(match->radius_mm, inner, 1e-6);
    EXPECT_NEAR(match->nominal_angle_deg,
                std::abs(c.spec.bend_angles_deg[static_cast<std::size_t>(e.bend_index)]), 1e-6);
    const int la = line_of_flange[static_cast<std::size_t>(match->flange_a)];
    const int lb = line_of_flange[static_cast<std::size_t>(match->flange_b)];
    EXPECT_EQ(std::min(la, lb), e.bend_index);
    EXPECT_EQ(std::max(la, lb), e.bend_index + 1);
  }
}

INSTANTIATE_TEST_SUITE_P(
    Profiles, CadSegmentationProfiles,
    ::testing::Combine(::testing::Values(Case{"L", l_profile(40, 30, 90, 3)},
                                         Case{"U", u_profile(25, 50, 90, 2)},
                                         Case{"hat", hat_profile(20, 30, 40, 75, 4)},
                                         Case{"Z", z_profile(30, 40, 120, 5)},
                                         Case{"L_solid", thick(l_profile(40, 30, 90, 3))},
                                         Case{"U_solid", thick(u_profile(25, 50, 90, 2))},
                                         Case{"hat_solid", thick(hat_profile(20, 30, 40, 75, 4))},
                                         Case{"Z_solid", thick(z_profile(30, 40, 120, 5))}),
                       ::testing::Values("built", "igs", "step")),
    [](const auto& param_info) {
      return std::string(std::get<0>(param_info.param).name) + "_" + std::get<1>(param_info.param);
    });

TEST(CadSegmentation, AdjacencyGraphOfAnLProfile) {
  const auto shape = make_profile_shape(l_profile(40, 30, 90, 3));
  ASSERT_TRUE(shape);
  const auto faces = describe_faces(*shape);
  ASSERT_EQ(faces.size(), 3u);
  int planes = 0, cylinders = 0;
  for (const auto& f : faces) {
    planes += f.type == "plane";
    cylinders += f.type == "cylinder";
    if (f.type == "cylinder") {
      EXPECT_EQ(f.neighbors.size(), 2u);  // the two flanges
      EXPECT_NEAR(f.radius_mm, 3.0, 1e-12);
      EXPECT_NEAR(f.area_mm2, 3.0 * std::numbers::pi / 2 * 60.0, 1e-6);
    } else {
      EXPECT_EQ(f.neighbors.size(), 1u);  // the bend
    }
  }
  EXPECT_EQ(planes, 2);
  EXPECT_EQ(cylinders, 1);
  EXPECT_TRUE(describe_faces(CadShape{}).empty());
  EXPECT_TRUE(segment_cad(CadShape{}).bends.empty());
}

// The real bent bracket (build123d, 3 mm, outer fillet R3 and a sharp inner corner): one 90
// degree bend of inner radius 0 between its two flanges.
TEST(CadSegmentation, RealBentBrackets) {
  const auto bracket = load_cad(shared_cad("nema-17-bracket.step"));
  ASSERT_TRUE(bracket) << bracket.message();
  const auto s = segment_cad(*bracket);
  print("nema-17-bracket.step", s);
  ASSERT_EQ(s.bends.size(), 1u);
  EXPECT_NEAR(s.bends[0].nominal_angle_deg, 90.0, 1e-6);
  EXPECT_NEAR(s.bends[0].radius_mm, 0.0, 1e-6);
  EXPECT_GE(s.flanges.size(), 2u);

  const auto roof = load_cad(shared_cad("steel-sheets-2000mm.step"));
  ASSERT_TRUE(roof) << roof.message();
  const auto r = segment_cad(*roof);
  print("steel-sheets-2000mm.step", r);
  // A trapezoidal sheet: a chain of flanges, one bend between each two neighbours.
  EXPECT_GE(r.bends.size(), 4u);
  EXPECT_EQ(r.bends.size() + 1, r.flanges.size());
  for (const auto& b : r.bends) {
    EXPECT_GT(b.nominal_angle_deg, 1.0);
    EXPECT_LT(b.nominal_angle_deg, 179.0);
    EXPECT_NEAR(std::abs(b.axis_direction.y()), 1.0, 1e-6);  // the sheet runs along y
  }
}

}  // namespace
}  // namespace springscan::analysis
