// The statistics of `springscan trend` (report/trend.hpp) against values worked out by hand in
// the comments, the reading of a report store, the page, and the CLI end to end.
#include "report/trend.hpp"

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <sstream>

#include "report/trend_html.hpp"
#include "tests/support/test_paths.hpp"

namespace springscan::report {
namespace {

namespace fs = std::filesystem;

/// [0, 1] repeated `pairs` times, then `tail`.
std::vector<double> alternating(int pairs, const std::vector<double>& tail) {
  std::vector<double> v;
  for (int i = 0; i < pairs; ++i) v.insert(v.end(), {0.0, 1.0});
  v.insert(v.end(), tail.begin(), tail.end());
  return v;
}

std::vector<std::size_t> flagged_with(const ControlChart& c, std::uint8_t rule) {
  std::vector<std::size_t> out;
  for (std::size_t i = 0; i < c.rules.size(); ++i)
    if (c.rules[i] & rule) out.push_back(i);
  return out;
}

TEST(TrendStatistics, IndividualsChartLimitsCpAndCpkByHand) {
  // x = 1 3 2 4 2: X-bar = 12/5 = 2.4; MR = 2 1 2 2, MR-bar = 7/4 = 1.75;
  // sigma = 1.75/1.128; UCL = 2.4 + 2.66 * 1.75 = 7.055, LCL = 2.4 - 4.655 = -2.255;
  // MR UCL = 3.267 * 1.75 = 5.71725. Limits 0..6: Cp = 6 / (6 sigma) = 1.128/1.75;
  // Cpk = min(6 - 2.4, 2.4 - 0) / (3 sigma) = 2.4 * 1.128 / 5.25.
  const ControlChart c = control_chart({1, 3, 2, 4, 2}, 0.0, 6.0);
  EXPECT_EQ(c.n, 5u);
  EXPECT_DOUBLE_EQ(c.mean, 2.4);
  EXPECT_EQ(c.moving_range, (std::vector<double>{2, 1, 2, 2}));
  EXPECT_DOUBLE_EQ(c.mr_bar, 1.75);
  EXPECT_DOUBLE_EQ(c.sigma, 1.75 / 1.128);
  EXPECT_NEAR(c.ucl, 7.055, 1e-12);
  EXPECT_NEAR(c.lcl, -2.255, 1e-12);
  EXPECT_NEAR(c.mr_ucl, 5.71725, 1e-12);
  ASSERT_TRUE(c.cp && c.cpk);
  EXPECT_NEAR(*c.cp, 1.128 / 1.75, 1e-12);
  EXPECT_NEAR(*c.cpk, 2.4 * 1.128 / 5.25, 1e-12);
  EXPECT_EQ(c.points_flagged, 0u);
  // One-sided (an upper limit only, as for the deviation): no Cp, Cpk = (6 - 2.4) / (3 sigma).
  const ControlChart upper = control_chart({1, 3, 2, 4, 2}, std::nullopt, 6.0);
  EXPECT_FALSE(upper.cp);
  ASSERT_TRUE(upper.cpk);
  EXPECT_NEAR(*upper.cpk, 3.6 * 1.128 / 5.25, 1e-12);
}

TEST(TrendStatistics, EmptyTinyAndConstantInputs) {
  const ControlChart empty = control_chart({}, -1.0, 1.0);
  EXPECT_EQ(empty.n, 0u);
  EXPECT_TRUE(empty.rules.empty());
  const ControlChart one = control_chart({0.5}, -1.0, 1.0);
  EXPECT_DOUBLE_EQ(one.mean, 0.5);
  EXPECT_TRUE(one.moving_range.empty());
  EXPECT_FALSE(one.cp);  // no spread known: no capability
  const ControlChart flat = control_chart({2, 2, 2, 2, 2, 2, 2, 2, 2}, 0.0, 3.0);
  EXPECT_DOUBLE_EQ(flat.sigma, 0.0);
  EXPECT_FALSE(flat.cpk);
  EXPECT_EQ(flat.points_flagged, 0u);
}

TEST(TrendStatistics, Rule1OnePointBeyondThreeSigma) {
  // 0 1 x10, then 10: X-bar = 20/21 = 0.952, MR-bar = (19 + 9)/20 = 1.4, sigma = 1.241;
  // (10 - 0.952) / 1.241 = 7.3 sigma. The alternating points stay within 0.8 sigma.
  const ControlChart c = control_chart(alternating(10, {10.0}), std::nullopt, std::nullopt);
  EXPECT_NEAR(c.mr_bar, 1.4, 1e-12);
  EXPECT_EQ(flagged_with(c, kRuleBeyond3Sigma), std::vector<std::size_t>{20});
  EXPECT_EQ(c.points_flagged, 1u);
}

TEST(TrendStatistics, Rule2TwoOfThreeBeyondTwoSigma) {
  // 0 1 x10, then 3 3: X-bar = 16/22 = 0.727, MR-bar = (19 + 2 + 0)/21 = 1, sigma = 0.8865;
  // z(3) = 2.273 / 0.8865 = 2.56: beyond 2 sigma, within 3.
  const ControlChart c = control_chart(alternating(10, {3.0, 3.0}), std::nullopt, std::nullopt);
  EXPECT_NEAR(c.mr_bar, 1.0, 1e-12);
  EXPECT_EQ(flagged_with(c, kRule2Of3Beyond2Sigma), (std::vector<std::size_t>{20, 21}));
  EXPECT_TRUE(flagged_with(c, kRuleBeyond3Sigma).empty());
  EXPECT_EQ(c.points_flagged, 2u);
}

TEST(TrendStatistics, Rule3FourOfFiveBeyondOneSigma) {
  // 0 1 x10, then 2 2 2 2: X-bar = 18/24 = 0.75, MR-bar = (19 + 1)/23 = 0.8696,
  // sigma = 0.7709; z(2) = 1.25 / 0.7709 = 1.62: beyond 1 sigma, within 2. The run above the
  // centre line is 5 long (the last 1 and the four 2s): no rule 4.
  const ControlChart c =
      control_chart(alternating(10, {2.0, 2.0, 2.0, 2.0}), std::nullopt, std::nullopt);
  EXPECT_NEAR(c.mr_bar, 20.0 / 23.0, 1e-12);
  EXPECT_EQ(flagged_with(c, kRule4Of5Beyond1Sigma), (std::vector<std::size_t>{20, 21, 22, 23}));
  EXPECT_EQ(c.points_flagged, 4u);
}

TEST(TrendStatistics, Rule4EightOnOneSide) {
  // 1 2 x4, then -1 -2 x4: X-bar = 0, MR-bar = (14 + 3)/15, sigma = 1.0047; z(2) = 1.99 and
  // z(1) = 0.995, so no other rule; both runs of 8 break rule 4.
  const ControlChart c = control_chart({1, 2, 1, 2, 1, 2, 1, 2, -1, -2, -1, -2, -1, -2, -1, -2},
                                       std::nullopt, std::nullopt);
  EXPECT_NEAR(c.mean, 0.0, 1e-12);
  EXPECT_NEAR(c.mr_bar, 17.0 / 15.0, 1e-12);
  EXPECT_EQ(flagged_with(c, kRule8OnOneSide).size(), 16u);
  EXPECT_EQ(c.points_flagged, 16u);
  for (const std::uint8_t bits : c.rules) EXPECT_EQ(bits, kRule8OnOneSide);
  // Seven on one side are not enough.
  const ControlChart seven =
      control_chart({1, 2, 1, 2, 1, 2, 1, -1, -2, -1, -2, -1, -2, -1}, std::nullopt, std::nullopt);
  EXPECT_TRUE(flagged_with(seven, kRule8OnOneSide).empty());
}

v1::InspectionReport make_report(const std::string& part, int seq, const std::string& utc,
                                 std::vector<double> springback, double p95, double max) {
  v1::InspectionReport r;
  r.set_schema("springscan.report.v1");
  r.set_result_seq(static_cast<std::uint32_t>(seq));
  r.set_job_id(100 + seq);
  r.set_created_utc(utc);
  r.mutable_input()->set_part_id(part);
  for (std::size_t i = 0; i < springback.size(); ++i) {
    v1::Bend* b = r.add_bends();
    b->set_id(static_cast<int>(i + 1));
    b->set_measured(std::isfinite(springback[i]));
    b->set_springback_deg(std::isfinite(springback[i]) ? springback[i] : 0.0);
    b->set_angle_tolerance_deg(1.0);
  }
  r.mutable_deviation()->set_points(1000);
  r.mutable_deviation()->set_p95(p95);
  r.mutable_deviation()->set_max(max);
  r.mutable_deviation()->set_min(-0.5 * max);
  r.mutable_deviation()->set_tolerance_mm(0.5);
  return r;
}

TEST(TrendCharacteristics, PerPartAndBendSortedByCpk) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const std::vector<v1::InspectionReport> reports = {
      make_report("1", 1, "2026-12-01T10:00:00Z", {0.1, 0.8}, 0.10, 0.20),
      make_report("1", 2, "2026-12-01T10:01:00Z", {0.3, nan}, 0.12, 0.22),  // bend 2 not measured
      make_report("1", 3, "2026-12-01T10:02:00Z", {0.2, 0.9}, 0.11, 0.40),
      make_report("2", 4, "2026-12-01T10:03:00Z", {0.0}, 0.05, 0.10),
  };
  const auto cs = collect_characteristics(reports);
  ASSERT_EQ(cs.size(), 4u + 3u);  // part 1: 2 bends + 2 deviation figures; part 2: 1 + 2
  std::map<std::string, const Characteristic*> by_name;
  for (const auto& c : cs) by_name[c.part_id + "/" + c.name] = &c;
  const Characteristic& bend1 = *by_name.at("1/bend 1 springback");
  EXPECT_EQ(bend1.values, (std::vector<double>{0.1, 0.3, 0.2}));
  EXPECT_EQ(bend1.unit, "deg");
  EXPECT_EQ(bend1.lsl, -1.0);
  EXPECT_EQ(bend1.usl, 1.0);
  EXPECT_EQ(bend1.labels[1], "seq 2, job 102, 2026-12-01T10:01:00Z");
  EXPECT_EQ(by_name.at("1/bend 2 springback")->values, (std::vector<double>{0.8, 0.9}));
  // max |d| = max(-min, max); tolerance above only.
  const Characteristic& max = *by_name.at("1/deviation max |d|");
  EXPECT_EQ(max.values, (std::vector<double>{0.20, 0.22, 0.40}));
  EXPECT_FALSE(max.lsl);
  EXPECT_EQ(max.usl, 0.5);
  // Sorted by Cpk, lowest first; one value (part 2) has no sigma, so no Cpk: last.
  for (std::size_t i = 1; i < cs.size(); ++i) {
    if (!cs[i].chart.cpk) continue;
    ASSERT_TRUE(cs[i - 1].chart.cpk);
    EXPECT_LE(*cs[i - 1].chart.cpk, *cs[i].chart.cpk);
  }
  EXPECT_EQ(cs.back().part_id, "2");
  // bend 2: 0.8, 0.9: X-bar 0.85, MR-bar 0.1, Cpk = (1 - 0.85) / (3 * 0.1 / 1.128).
  EXPECT_NEAR(*by_name.at("1/bend 2 springback")->chart.cpk, 0.15 * 1.128 / 0.3, 1e-12);
}

// Each flange's flatness, curl and twist, and each bend's angle spread, when the report has them,
// with the verdict's limits in force.
TEST(TrendCharacteristics, FlangeShapeAndAngleSpread) {
  std::vector<v1::InspectionReport> reports;
  for (int k = 1; k <= 3; ++k) {
    v1::InspectionReport r =
        make_report("5", k, "2026-12-02T08:0" + std::to_string(k) + ":00Z", {0.5}, 0.1, 0.2);
    r.mutable_settings()->mutable_verdict()->set_max_flatness_mm(1.0);
    r.mutable_bends(0)->add_angle_along_bend()->set_angle_deg(88.0);
    r.mutable_bends(0)->set_angle_spread_deg(0.1 * k);
    v1::Segment* wall = r.add_segments();
    wall->set_id(2);
    wall->set_points(500);
    wall->set_flatness_mm(0.3 + 0.1 * k);
    if (k != 2) wall->set_curl_radius_mm(-300.0 - k);  // flat within noise in report 2
    wall->set_twist_deg_per_100mm(0.05 * k);
    reports.push_back(r);
  }
  std::map<std::string, const Characteristic*> by_name;
  const auto cs = collect_characteristics(reports);
  for (const auto& c : cs) by_name[c.name] = &c;
  EXPECT_EQ(by_name.at("bend 1 angle spread")->values,
            (std::vector<double>{0.1, 0.2, 0.30000000000000004}));
  const Characteristic& flat = *by_name.at("flange 2 flatness");
  EXPECT_EQ(flat.values.size(), 3u);
  EXPECT_EQ(flat.usl, 1.0);
  EXPECT_FALSE(flat.lsl);
  EXPECT_EQ(by_name.at("flange 2 curl radius")->values, (std::vector<double>{-301.0, -303.0}));
  EXPECT_EQ(by_name.at("flange 2 twist")->unit, "deg/100 mm");
  EXPECT_EQ(by_name.at("flange 2 twist")->values.size(), 3u);
}

// Each value keeps its U and its decision; the part decisions are counted; the page shows
// value +- U, the median U and the undecided count (issue 41).
TEST(TrendCharacteristics, CarryUncertaintiesAndDecisions) {
  std::vector<v1::InspectionReport> reports;
  const v1::Verdict::Decision decided[] = {v1::Verdict::PASS, v1::Verdict::UNDECIDED,
                                           v1::Verdict::FAIL, v1::Verdict::UNDECIDED};
  for (int k = 0; k < 4; ++k) {
    auto r = make_report("1", k + 1, "2026-12-01T10:0" + std::to_string(k) + ":00Z",
                         {0.9 + 0.05 * k}, 0.1, 0.2);
    r.mutable_verdict()->set_decision(decided[k]);
    r.mutable_bends(0)->set_springback_uncertainty_deg(0.125 + 0.125 * k);
    r.mutable_bends(0)->set_decision(k == 0   ? v1::CONFORMING
                                     : k == 2 ? v1::NONCONFORMING
                                              : v1::UNDECIDED);
    r.mutable_deviation()->set_uncertainty_mm(0.03);  // of p95: the default statistic
    r.mutable_deviation()->set_decision(v1::CONFORMING);
    reports.push_back(r);
  }
  reports.push_back(make_report("1", 5, "2026-12-01T10:05:00Z", {0.5}, 0.1, 0.2));  // no decision
  const auto cs = collect_characteristics(reports);
  std::map<std::string, const Characteristic*> by_name;
  for (const auto& c : cs) by_name[c.name] = &c;
  const Characteristic& bend = *by_name.at("bend 1 springback");
  EXPECT_EQ(bend.uncertainties, (std::vector<double>{0.125, 0.25, 0.375, 0.5, 0.0}));
  EXPECT_EQ(bend.undecided, 2u);
  EXPECT_EQ(bend.nonconforming, 1u);
  EXPECT_EQ(by_name.at("deviation p95")->uncertainties[0], 0.03);
  EXPECT_EQ(by_name.at("deviation max |d|")->uncertainties[0], 0.0) << "not the statistic judged";
  const DecisionCounts counts = decision_counts(reports);
  EXPECT_EQ(counts.pass, 1u);
  EXPECT_EQ(counts.fail, 1u);
  EXPECT_EQ(counts.undecided, 2u);
  EXPECT_EQ(counts.none, 1u);
  TrendPageInfo info;
  info.decisions = counts;
  const std::string html = render_trend_html(cs, info);
  EXPECT_NE(html.find("1 PASS, 1 FAIL, 2 UNDECIDED, 1 without a decision"), std::string::npos);
  EXPECT_NE(html.find("0.9500 &plusmn; 0.2500 deg"), std::string::npos);
  EXPECT_NE(html.find("<td>0.3750</td><td>2</td><td>1</td>"), std::string::npos)
      << "median U of the values that have one, undecided, nonconforming";
}

class TrendFiles : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("springscan_trend_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    // A station's report store, written out of time order, with an unfinished write.
    for (int k = 1; k <= 12; ++k) {
      char name[32];
      std::snprintf(name, sizeof name, "r%012d", k);
      fs::create_directories(dir_ / "store" / name);
      char utc[32];
      std::snprintf(utc, sizeof utc, "2026-12-01T10:%02d:00Z", k == 12 ? 0 : k);
      const double sb = 0.2 + 0.05 * (k % 3) + (k == 9 ? 0.7 : 0.0);
      std::ofstream(dir_ / "store" / name / "report.pb", std::ios::binary)
          << make_report("7", k, utc, {sb, 0.4}, 0.1 + 0.01 * k, 0.2).SerializeAsString();
    }
    fs::create_directories(dir_ / "store" / ".tmp-r000000000013");
    std::ofstream(dir_ / "store" / ".tmp-r000000000013" / "report.pb") << "partial";
    std::ofstream(dir_ / "store" / "junk.pb") << "not a report";
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path dir_;
};

TEST_F(TrendFiles, ReadsAStoreInTimeOrderAndSkipsWhatIsNotAReport) {
  for (unsigned threads : {1u, 4u}) {
    auto input = read_reports({(dir_ / "store").string()}, threads);
    ASSERT_TRUE(input.ok()) << input.message();
    ASSERT_EQ(input->reports.size(), 12u);
    EXPECT_EQ(input->reports.front().result_seq(), 12u);  // created first
    EXPECT_EQ(input->reports.back().result_seq(), 11u);
    ASSERT_EQ(input->skipped.size(), 1u);  // junk.pb; the unfinished write is not looked at
    EXPECT_NE(input->skipped[0].find("junk.pb: not an InspectionReport"), std::string::npos);
  }
  EXPECT_FALSE(read_reports({(dir_ / "absent").string()}).ok());
  fs::create_directories(dir_ / "empty");
  auto none = read_reports({(dir_ / "empty").string()});
  ASSERT_FALSE(none.ok());
  EXPECT_NE(none.message().find("no report.pb found"), std::string::npos);
}

TEST_F(TrendFiles, PageHasTheTableAndOneChartPairPerCharacteristic) {
  auto input = read_reports({(dir_ / "store").string()});
  ASSERT_TRUE(input.ok());
  const auto cs = collect_characteristics(input->reports);
  TrendPageInfo info;
  info.reports = input->reports.size();
  info.sources = {"store <A&B>"};
  const std::string html = render_trend_html(cs, info);
  const auto count = [&](const std::string& what) {
    std::size_t n = 0;
    for (auto at = html.find(what); at != std::string::npos; at = html.find(what, at + 1)) ++n;
    return n;
  };
  EXPECT_EQ(count("<tr class=\"characteristic\">"), cs.size());
  EXPECT_EQ(count("<svg class=\"individuals\""), cs.size());
  EXPECT_EQ(count("<svg class=\"moving-range\""), cs.size());
  EXPECT_NE(html.find("store &lt;A&amp;B&gt;"), std::string::npos);
  std::size_t flagged = 0;
  for (const auto& c : cs) flagged += c.chart.points_flagged;
  EXPECT_GT(flagged, 0u);  // record 9 jumps by 0.7 deg
  EXPECT_EQ(count("class=\"flagged\""), flagged);
  EXPECT_EQ(html.find("<script"), std::string::npos);
  EXPECT_EQ(html.find("http://", html.find("<body")), html.find("http://www.w3.org/2000/svg"));
}

TEST_F(TrendFiles, CliWritesThePage) {
  const fs::path out = dir_ / "trend.html";
  const std::string command = std::string(springscan::test_paths::kSpringscan) + " trend " +
                              (dir_ / "store").string() + " --out " + out.string() + " 2> " +
                              (dir_ / "err.txt").string();
  const int status = std::system(command.c_str());
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 0);
  std::ifstream in(out);
  std::stringstream html;
  html << in.rdbuf();
  EXPECT_NE(html.str().find("bend 1 springback"), std::string::npos);
  std::ifstream err_in(dir_ / "err.txt");
  std::stringstream err;
  err << err_in.rdbuf();
  EXPECT_NE(err.str().find("skipped"), std::string::npos) << err.str();
  const std::string bad = std::string(springscan::test_paths::kSpringscan) + " trend " +
                          (dir_ / "absent").string() + " --out " + out.string() + " 2> /dev/null";
  const int bad_status = std::system(bad.c_str());
  EXPECT_EQ(WEXITSTATUS(bad_status), 2);
}

}  // namespace
}  // namespace springscan::report
