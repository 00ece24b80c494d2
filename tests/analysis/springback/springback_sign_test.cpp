// The sign of springback on real production parts: every bend of the
// openamr parts and the nema-17 bracket, with either side of the sheet as each flange's CAD
// reference, opened and closed by a known angle, gives that angle back with its sign; closed
// hems (180 degrees) do not wrap to 360.
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <numbers>

#include "analysis/cad/model.hpp"
#include "analysis/springback/springback.hpp"
#include "tests/analysis/cad_test_util.hpp"

namespace springscan::analysis {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

const PartModel& part(const std::string& name) {
  static std::map<std::string, PartModel> loaded;
  auto it = loaded.find(name);
  if (it == loaded.end()) {
    auto model = load_part_model(testing::shared_cad(name));
    EXPECT_TRUE(model.ok()) << model.message();
    it = loaded.emplace(name, model.ok() ? std::move(*model) : PartModel{}).first;
  }
  return it->second;
}

const Flange& flange(const PartModel& m, int id) {
  for (const Flange& f : m.segmentation.flanges)
    if (f.id == id) return f;
  throw std::runtime_error("no flange " + std::to_string(id));
}

// The mean of a flange's model samples, from the axis, across the axis.
Vec3 from_axis(const PartModel& m, const Flange& f, const Bend& bend) {
  Vec3 sum = Vec3::Zero();
  int n = 0;
  for (std::size_t i = 0; i < m.samples.size(); ++i)
    if (std::find(f.face_ids.begin(), f.face_ids.end(), m.samples.face_ids[i]) != f.face_ids.end())
      sum += m.samples.points[i], ++n;
  const Vec3 d = bend.axis_direction.normalized();
  Vec3 v = sum / std::max(n, 1) - bend.axis_point;
  return v - v.dot(d) * d;
}

// The same flange described by the other side of the sheet.
Flange other_side(Flange f) {
  f.point -= f.thickness_mm * f.normal;
  f.normal = -f.normal;
  return f;
}

// The local fit of flange b when the produced part opened the bend by `springback_deg`: the
// data's flange b is the model's turned back about the bend axis, so the fit (data onto model)
// turns it forward. "Opened" is decided from the flanges' material, independently of normals:
// opening widens the angle between the two flanges as seen from the axis.
FlangeFit opened_fit(const PartModel& m, const Bend& bend, double springback_deg) {
  const Vec3 ua = from_axis(m, flange(m, bend.flange_a), bend);
  const Vec3 ub = from_axis(m, flange(m, bend.flange_b), bend);
  Vec3 w = bend.axis_direction.normalized();
  if (ua.cross(ub).dot(w) > 0.0) w = -w;  // the sense in which the sheet turns from a to b
  const Eigen::AngleAxisd turn(springback_deg * kDeg, w);
  FlangeFit fit;
  fit.fitted = true;
  fit.fit.T_model_subset =
      Eigen::Translation3d(bend.axis_point) * turn * Eigen::Translation3d(-bend.axis_point);
  // Sanity of the construction: the data's flange b (turned back) is wider open from a.
  const Vec3 ub_data = turn.inverse() * ub;
  const double before = std::atan2(ua.cross(ub).norm(), ua.dot(ub));
  const double after = std::atan2(ua.cross(ub_data).norm(), ua.dot(ub_data));
  EXPECT_EQ(after > before, springback_deg > 0.0);
  return fit;
}

void expect_signs(const std::string& name, std::size_t bends_expected) {
  const PartModel& m = part(name);
  ASSERT_EQ(m.segmentation.bends.size(), bends_expected) << name;
  FlangeFit identity;
  identity.fitted = true;
  for (const Bend& bend : m.segmentation.bends) {
    const Flange& fa = flange(m, bend.flange_a);
    const Flange& fb = flange(m, bend.flange_b);
    ASSERT_GT(fa.thickness_mm, 0.0) << name << " flange " << fa.id;
    for (double springback : {1.52, -0.49, 2.74, 0.0}) {
      const FlangeFit b = opened_fit(m, bend, springback);
      for (int sides = 0; sides < 4; ++sides) {
        const Flange ra = sides & 1 ? other_side(fa) : fa;
        const Flange rb = sides & 2 ? other_side(fb) : fb;
        const BendMeasurement r = measure_bend(bend, ra, rb, identity, b);
        ASSERT_TRUE(r.measured);
        EXPECT_NEAR(r.springback_deg, springback, 1e-6)
            << name << " bend " << bend.id << " nominal " << bend.nominal_angle_deg
            << " reference sides " << sides;
        EXPECT_NEAR(r.measured_angle_deg, bend.nominal_angle_deg - springback, 1e-6);
      }
    }
  }
}

TEST(SpringbackSign, MotorBracket) {
  expect_signs("openamr-MMP.03.00.00.003_Motor_bracket.step", 4);
}
TEST(SpringbackSign, CoverFlangeWithHems) {
  expect_signs("openamr-MMP.01.00.00.002_Cover_flange.step", 8);
}
TEST(SpringbackSign, SidePanel) { expect_signs("openamr-MMP.00.00.00.003_Side_panel.step", 16); }
TEST(SpringbackSign, FrontPanel) { expect_signs("openamr-MMP.00.00.00.001_Front_panel.step", 4); }
TEST(SpringbackSign, Nema17Bracket) { expect_signs("nema-17-bracket.step", 1); }

}  // namespace
}  // namespace springscan::analysis
