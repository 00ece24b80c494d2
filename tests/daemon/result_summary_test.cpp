#include "daemon/result_summary.hpp"

#include <google/protobuf/struct.pb.h>
#include <google/protobuf/util/json_util.h>
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace springscan::daemon {
namespace {

google::protobuf::Struct parse(const std::string& json) {
  google::protobuf::Struct s;
  EXPECT_TRUE(google::protobuf::util::JsonStringToMessage(json, &s).ok()) << json;
  return s;
}

TEST(ResultSummaryTest, HoldsTheIdsVerdictDeviationAndBendTable) {
  v1::InspectionReport r;
  r.set_job_id(42);
  r.set_result_code(1);
  r.set_created_utc("2026-12-01T18:00:00Z");
  r.mutable_input()->set_part_id("7");
  r.mutable_verdict()->set_pass(false);
  r.mutable_verdict()->add_reasons("bend 0: springback 2.1 deg > 1 \"tol\"\n");
  r.mutable_deviation()->set_max(0.25);
  r.mutable_deviation()->set_p95(0.125);
  v1::Bend* b = r.add_bends();
  b->set_id(3);
  b->set_springback_deg(-0.1);
  b->set_measured(true);
  b->set_angle_spread_deg(0.25);
  b->add_angle_along_bend()->set_angle_deg(89.0);
  v1::Segment* curled = r.add_segments();
  curled->set_id(1);
  curled->set_flatness_mm(0.8);
  curled->set_curl_radius_mm(-420.0);
  curled->set_twist_deg_per_100mm(0.3);
  r.add_segments()->set_id(2);  // flat: no curl radius, no twist
  const std::string json = result_summary_json(r, PublishedIds{"press-4", 513, 90001, 24466});
  EXPECT_EQ(json.find('\n'), std::string::npos);  // one line
  const auto s = parse(json);
  const auto& f = s.fields();
  EXPECT_EQ(f.at("schema").string_value(), "springscan.result.v1");
  EXPECT_EQ(f.at("station").string_value(), "press-4");
  EXPECT_EQ(f.at("boot_id").number_value(), 513);
  EXPECT_EQ(f.at("record").number_value(), 90001);
  EXPECT_EQ(f.at("result_seq").number_value(), 24466);
  EXPECT_EQ(f.at("job_id").number_value(), 42);
  EXPECT_EQ(f.at("part_id").string_value(), "7");
  EXPECT_EQ(f.at("result_code").number_value(), 1);
  EXPECT_FALSE(f.at("pass").bool_value());
  EXPECT_EQ(f.at("reasons").list_value().values(0).string_value(),
            "bend 0: springback 2.1 deg > 1 \"tol\"\n");
  EXPECT_EQ(f.at("deviation").struct_value().fields().at("p95_mm").number_value(), 0.125);
  const auto& bend = f.at("bends").list_value().values(0).struct_value().fields();
  EXPECT_EQ(bend.at("id").number_value(), 3);
  EXPECT_EQ(bend.at("springback_deg").number_value(), -0.1);  // shortest round trip, exact
  EXPECT_TRUE(bend.at("measured").bool_value());
  EXPECT_EQ(bend.at("angle_spread_deg").number_value(), 0.25);
  EXPECT_EQ(bend.count("measured_radius_mm"), 0u);  // not fitted: absent
  const auto& flanges = f.at("flanges").list_value();
  ASSERT_EQ(flanges.values_size(), 2);
  const auto& one = flanges.values(0).struct_value().fields();
  EXPECT_EQ(one.at("flatness_mm").number_value(), 0.8);
  EXPECT_EQ(one.at("curl_radius_mm").number_value(), -420.0);
  EXPECT_EQ(one.at("twist_deg_per_100mm").number_value(), 0.3);
  EXPECT_EQ(flanges.values(1).struct_value().fields().count("curl_radius_mm"), 0u);
}

// The decision, the rule that made it and each U travel with the result (issue 41); a report
// without decisions (a failed scan) has no decision field, never a default read as a verdict.
TEST(ResultSummaryTest, CarriesTheDecisionsAndTheirUncertainties) {
  v1::InspectionReport r;
  r.set_result_code(6);
  r.mutable_verdict()->set_decision(v1::Verdict::UNDECIDED);
  r.mutable_verdict()->set_decision_rule(v1::VerdictSettings::GUARD_BAND);
  r.mutable_deviation()->set_p95(0.47);
  r.mutable_deviation()->set_uncertainty_mm(0.05);
  r.mutable_deviation()->set_decision(v1::UNDECIDED);
  v1::Bend* b = r.add_bends();
  b->set_springback_deg(0.98);
  b->set_springback_uncertainty_deg(0.125);
  b->set_angle_uncertainty_deg(0.25);
  b->set_decision(v1::UNDECIDED);
  v1::Segment* seg = r.add_segments();
  seg->set_flatness_uncertainty_mm(0.03);
  seg->set_curl_radius_mm(-300.0);
  seg->set_curl_radius_uncertainty_mm(40.0);
  seg->set_shape_decision(v1::CONFORMING);
  const auto s = parse(result_summary_json(r, {}));
  const auto& f = s.fields();
  EXPECT_FALSE(f.at("pass").bool_value());
  EXPECT_EQ(f.at("decision").string_value(), "UNDECIDED");
  EXPECT_EQ(f.at("decision_rule").string_value(), "GUARD_BAND");
  const auto& dev = f.at("deviation").struct_value().fields();
  EXPECT_EQ(dev.at("uncertainty_mm").number_value(), 0.05);
  EXPECT_EQ(dev.at("decision").string_value(), "UNDECIDED");
  const auto& bend = f.at("bends").list_value().values(0).struct_value().fields();
  EXPECT_EQ(bend.at("springback_uncertainty_deg").number_value(), 0.125);
  EXPECT_EQ(bend.at("angle_uncertainty_deg").number_value(), 0.25);
  EXPECT_EQ(bend.at("decision").string_value(), "UNDECIDED");
  const auto& flange = f.at("flanges").list_value().values(0).struct_value().fields();
  EXPECT_EQ(flange.at("flatness_uncertainty_mm").number_value(), 0.03);
  EXPECT_EQ(flange.at("curl_radius_uncertainty_mm").number_value(), 40.0);
  EXPECT_EQ(flange.at("shape_decision").string_value(), "CONFORMING");
  v1::InspectionReport failed_scan;
  failed_scan.set_result_code(3);
  const auto none = parse(result_summary_json(failed_scan, {}));
  EXPECT_EQ(none.fields().count("decision"), 0u);
}

TEST(ResultSummaryTest, EmptyReportAndNonFiniteNumbersStayValidJson) {
  v1::InspectionReport r;
  r.set_cycle_time_ms(std::numeric_limits<double>::quiet_NaN());
  const auto s = parse(result_summary_json(r, {}));
  EXPECT_EQ(s.fields().at("cycle_time_ms").kind_case(), google::protobuf::Value::kNullValue);
  EXPECT_EQ(s.fields().at("bends").list_value().values_size(), 0);
  EXPECT_EQ(s.fields().count("deviation"), 0u);
}

// A check part's result carries its comparison (docs/plant-integration.md); others do not.
TEST(ResultSummaryTest, CheckPartResultCarriesCalibrationDrift) {
  v1::InspectionReport r;
  EXPECT_EQ(parse(result_summary_json(r, {})).fields().count("check"), 0u);
  v1::CheckResult* check = r.mutable_check();
  check->set_drift(true);
  v1::CheckItem* moved = check->add_items();
  moved->set_characteristic("bend 2 springback");
  moved->set_reference(0.4);
  moved->set_limit(0.1);
  moved->set_measured(0.625);
  moved->set_beyond(true);
  check->add_items()->set_characteristic("pose rotation z");  // not measured
  const auto s = parse(result_summary_json(r, {}));
  const auto& c = s.fields().at("check").struct_value().fields();
  EXPECT_TRUE(c.at("calibration_drift").bool_value());
  const auto& items = c.at("items").list_value();
  ASSERT_EQ(items.values_size(), 2);
  const auto& first = items.values(0).struct_value().fields();
  EXPECT_EQ(first.at("characteristic").string_value(), "bend 2 springback");
  EXPECT_EQ(first.at("measured").number_value(), 0.625);
  EXPECT_EQ(first.at("limit").number_value(), 0.1);
  EXPECT_TRUE(first.at("beyond").bool_value());
  EXPECT_EQ(items.values(1).struct_value().fields().count("measured"), 0u);
}

}  // namespace
}  // namespace springscan::daemon
