// Datum candidates of real parts (analysis/cad/datum_features.hpp), checked against the CAD
// itself: every slot listed is a stadium of the flange's skin with no material inside and
// material all round it, its ends cylinder faces of the slot's radius.
#include "analysis/cad/datum_features.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <numbers>

#include "analysis/cad/sampling.hpp"
#include "tests/simulators/parts/production_parts.hpp"

namespace springscan::analysis {
namespace {

// Distance of p's projection on the slot's plane to the slot's centre segment.
double to_centre_line(const SlotCandidate& s, const Vec3& p) {
  const Vec3 along = s.axis.cross(s.direction);
  const double half = 0.5 * (s.length_mm - s.width_mm);
  Vec3 v = p - s.centre;
  v -= v.dot(s.axis) * s.axis;
  const double t = std::clamp(v.dot(along), -half, half);
  return (v - t * along).norm();
}

class SlotCandidates : public ::testing::TestWithParam<std::string> {};

TEST_P(SlotCandidates, EachIsAStadiumCutThroughItsFlange) {
  const auto& cad = parts::testing::loaded_part(GetParam());
  const auto faces = describe_faces(cad.shape);
  const DatumCandidates c = datum_candidates(cad.shape, faces, cad.model.segmentation);
  ASSERT_FALSE(c.slots.empty()) << GetParam();
  auto samples = sample_cad(cad.shape, {.sample_count = 400000, .seed = 9});
  ASSERT_TRUE(samples) << samples.message();
  for (const SlotCandidate& s : c.slots) {
    const std::string what = GetParam() + " slot at " + ::testing::PrintToString(s.centre);
    EXPECT_NEAR(s.direction.norm(), 1.0, 1e-9);
    EXPECT_NEAR(s.direction.dot(s.axis), 0.0, 1e-9) << what;
    EXPECT_GT(s.length_mm, s.width_mm) << what;
    for (int id : s.face_ids) {
      EXPECT_EQ(faces[static_cast<std::size_t>(id)].type, "cylinder") << what;
      EXPECT_NEAR(faces[static_cast<std::size_t>(id)].radius_mm, 0.5 * s.width_mm, 0.02) << what;
    }
    // On the skin the centre lies on (and, for a solid, one thickness behind it): nothing
    // inside the stadium, and skin all round it.
    int inside = 0, around = 0;
    for (std::size_t i = 0; i < samples->size(); ++i) {
      const Vec3& p = samples->points[i];
      const double h = (p - s.centre).dot(s.axis);
      const bool on_skin = std::abs(h) < 0.01 || std::abs(h + s.thickness_mm) < 0.01;
      if (!on_skin || std::abs(samples->normals[i].dot(s.axis)) < 0.99) continue;
      const double r = to_centre_line(s, p);
      inside += r < 0.5 * s.width_mm - 0.05;
      around += r > 0.5 * s.width_mm && r < 0.5 * s.width_mm + 1.0;
    }
    EXPECT_EQ(inside, 0) << what << ": skin inside the slot";
    EXPECT_GT(around, 20) << what << ": no skin around the slot";
  }
}

INSTANTIATE_TEST_SUITE_P(
    RealParts, SlotCandidates,
    ::testing::Values("nema-17-bracket.step", "openamr-MMP.00.00.00.001_Front_panel.step",
                      "openamr-MMP.00.00.00.003_Side_panel.step"),
    [](const ::testing::TestParamInfo<std::string>& p) {
      return std::string(p.index == 0 ? "NemaBracket" : p.index == 1 ? "FrontPanel" : "SidePanel");
    });

// Every round hole listed is a disc of the flange's skin with no material inside and material
// all round it (in each of 12 sectors): the side panel's slots, whose ends lie on common axes
// across its two walls, were once listed as 4.3 mm holes (their half circles summed to one).
class HoleCandidates : public ::testing::TestWithParam<std::string> {};

TEST_P(HoleCandidates, EachIsARoundHoleThroughItsFlange) {
  const auto& cad = parts::testing::loaded_part(GetParam());
  const auto faces = describe_faces(cad.shape);
  const DatumCandidates c = datum_candidates(cad.shape, faces, cad.model.segmentation);
  auto samples = sample_cad(cad.shape, {.sample_count = 400000, .seed = 9});
  ASSERT_TRUE(samples) << samples.message();
  for (const HoleCandidate& h : c.holes) {
    const std::string what = GetParam() + " hole at " + ::testing::PrintToString(h.centre);
    const Vec3 e1 = h.axis.unitOrthogonal(), e2 = h.axis.cross(e1);
    const double r = 0.5 * h.diameter_mm;
    int inside = 0;
    std::array<int, 12> around{};
    for (std::size_t i = 0; i < samples->size(); ++i) {
      const Vec3 v = samples->points[i] - h.centre;
      const double z = v.dot(h.axis);
      const bool on_skin = std::abs(z) < 0.01 || std::abs(z + h.thickness_mm) < 0.01;
      if (!on_skin || std::abs(samples->normals[i].dot(h.axis)) < 0.99) continue;
      const double x = v.dot(e1), y = v.dot(e2), rho = std::hypot(x, y);
      inside += rho < r - 0.05;
      if (rho > r && rho < r + 1.5)
        ++around[static_cast<std::size_t>((std::atan2(y, x) + std::numbers::pi) /
                                          (2 * std::numbers::pi) * 12) %
                 12];
    }
    EXPECT_EQ(inside, 0) << what << ": skin inside the hole";
    for (std::size_t k = 0; k < around.size(); ++k)
      EXPECT_GT(around[k], 0) << what << ": no skin in sector " << k << " around it";
  }
}

INSTANTIATE_TEST_SUITE_P(RealParts, HoleCandidates,
                         ::testing::ValuesIn(parts::testing::production_parts()),
                         [](const ::testing::TestParamInfo<std::string>& p) {
                           std::string name;
                           for (char ch : p.param)
                             if (std::isalnum(static_cast<unsigned char>(ch))) name += ch;
                           return name;
                         });

// The side panel's four 4.3 x 8 mm slots on each wall, none a round hole.
TEST(HoleCandidates, SidePanelHasSlotsNotHoles) {
  const auto& cad = parts::testing::loaded_part("openamr-MMP.00.00.00.003_Side_panel.step");
  const DatumCandidates c =
      datum_candidates(cad.shape, describe_faces(cad.shape), cad.model.segmentation);
  EXPECT_TRUE(c.holes.empty()) << c.holes.size();
  EXPECT_EQ(c.slots.size(), 16u);
}

// Parts without slots list none (their half-circle faces are notches or corner reliefs).
TEST(SlotCandidates, NoneOnPartsWithoutSlots) {
  for (const std::string name : {"openamr-MMP.03.00.00.003_Motor_bracket.step",
                                 "openamr-MMP.01.00.00.002_Cover_flange.step"}) {
    const auto& cad = parts::testing::loaded_part(name);
    const DatumCandidates c =
        datum_candidates(cad.shape, describe_faces(cad.shape), cad.model.segmentation);
    EXPECT_TRUE(c.slots.empty()) << name << ": " << c.slots.size();
  }
}

}  // namespace
}  // namespace springscan::analysis
