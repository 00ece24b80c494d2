// The check part's comparison (report/check_part.hpp): a station unchanged is not flagged; a
// head turned by 0.2 degree (the result frame's pose turns with it) and a springback off its
// reference are; a characteristic not measured counts as drift.
#include "report/check_part.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <numbers>

namespace springscan::report {
namespace {

/// A report of the check part: bends with `springback`, the result frame turned by `turn_deg`
/// about z and moved by (1, 2, 3) mm.
v1::InspectionReport check_report(const std::vector<double>& springback, double turn_deg) {
  v1::InspectionReport r;
  r.mutable_input()->set_part_id("9");
  for (std::size_t i = 0; i < springback.size(); ++i) {
    v1::Bend* b = r.add_bends();
    b->set_id(static_cast<int>(i + 1));
    b->set_measured(true);
    b->set_springback_deg(springback[i]);
    b->set_angle_tolerance_deg(1.0);
  }
  const Eigen::Matrix3d R =
      Eigen::AngleAxisd(turn_deg * std::numbers::pi / 180.0, Eigen::Vector3d::UnitZ())
          .toRotationMatrix();
  const double t[3] = {1.0, 2.0, 3.0};
  for (int row = 0; row < 4; ++row)
    for (int col = 0; col < 4; ++col)
      r.mutable_alignment()->add_transform(row == 3   ? (col == 3 ? 1.0 : 0.0)
                                           : col == 3 ? t[row]
                                                      : R(row, col));
  return r;
}

v1::CheckPartConfig references() {
  v1::CheckPartConfig c;
  c.set_part_id(9);
  const auto add = [&](const char* name, double value, double limit) {
    v1::CheckReference* ref = c.add_reference();
    ref->set_characteristic(name);
    ref->set_value(value);
    ref->set_limit(limit);
  };
  add("bend 1 springback", 0.5, 0.1);
  add("pose rotation z", 0.0, 0.05);
  add("pose translation y", 2.0, 0.05);
  return c;
}

TEST(CheckPart, PoseAndTrendCharacteristics) {
  const auto measured = check_characteristics(check_report({0.5, 0.8}, 0.2));
  EXPECT_NEAR(measured.at("pose rotation z"), 0.2, 1e-12);
  EXPECT_NEAR(measured.at("pose rotation x"), 0.0, 1e-12);
  EXPECT_NEAR(measured.at("pose translation x"), 1.0, 1e-12);
  EXPECT_NEAR(measured.at("bend 2 springback"), 0.8, 1e-12);
  EXPECT_EQ(measured.count("bend 3 springback"), 0u);
}

TEST(CheckPart, AnUnchangedStationIsNotFlagged) {
  const v1::CheckResult r = check_part(check_report({0.52, 0.8}, 0.01), references());
  EXPECT_FALSE(r.drift());
  ASSERT_EQ(r.items_size(), 3);
  EXPECT_NEAR(r.items(0).measured(), 0.52, 1e-12);
  for (const auto& item : r.items()) EXPECT_FALSE(item.beyond()) << item.characteristic();
}

TEST(CheckPart, AHeadTurnedByAFifthOfADegreeIsCaught) {
  const v1::CheckResult r = check_part(check_report({0.5, 0.8}, 0.2), references());
  EXPECT_TRUE(r.drift());
  EXPECT_FALSE(r.items(0).beyond());
  EXPECT_TRUE(r.items(1).beyond());
  EXPECT_NEAR(r.items(1).measured(), 0.2, 1e-12);
}

TEST(CheckPart, SpringbackOffOrNotMeasuredIsDrift) {
  EXPECT_TRUE(check_part(check_report({0.65, 0.8}, 0.0), references()).drift());
  const v1::CheckResult missing = check_part(check_report({}, 0.0), references());
  EXPECT_TRUE(missing.drift());
  EXPECT_FALSE(missing.items(0).has_measured());
  EXPECT_TRUE(missing.items(0).beyond());
  EXPECT_FALSE(missing.items(1).beyond());
}

}  // namespace
}  // namespace springscan::report
