// The gauge studies over reports (report/msa.hpp), their pages, and `springscan msa` end to end:
// reports whose values are drawn from known distributions, the figures computed again here from
// the drawn values, and every refusal (too few reports, mixed part ids, an unbalanced study, a
// characteristic missing) with nothing written.
#include "report/msa.hpp"

#include <google/protobuf/util/json_util.h>
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>

#include "report/msa_html.hpp"
#include "tests/support/test_paths.hpp"

namespace springscan::report {
namespace {

namespace fs = std::filesystem;

/// A report of part "7" with two bends (angle tolerance 0.5 deg: T = 1 deg) and the deviation
/// figures (tolerance 0.4 mm).
v1::InspectionReport make_report(int seq, const std::string& serial, double bend1, double bend2,
                                 double p95) {
  v1::InspectionReport r;
  r.set_schema("springscan.report.v1");
  r.set_result_seq(static_cast<std::uint32_t>(seq));
  char utc[32];
  std::snprintf(utc, sizeof utc, "2026-12-01T%02d:%02d:00Z", 8 + seq / 60, seq % 60);
  r.set_created_utc(utc);
  r.mutable_input()->set_part_id("7");
  r.mutable_input()->set_part_serial(serial);
  for (const double sb : {bend1, bend2}) {
    v1::Bend* b = r.add_bends();
    b->set_id(r.bends_size());
    b->set_measured(std::isfinite(sb));
    b->set_springback_deg(std::isfinite(sb) ? sb : 0.0);
    b->set_angle_tolerance_deg(0.5);
  }
  r.mutable_deviation()->set_points(1000);
  r.mutable_deviation()->set_p95(p95);
  r.mutable_deviation()->set_max(p95 * 1.5);
  r.mutable_deviation()->set_min(-p95);
  r.mutable_deviation()->set_tolerance_mm(0.4);
  return r;
}

struct Drawn {
  std::vector<v1::InspectionReport> reports;
  std::vector<double> bend1, bend2;  ///< the drawn springback values, report order
};

/// `n` repeats of one reference part: bend 1 ~ N(0.42 + 0.004, 0.01), bend 2 ~ N(-0.2, 0.03).
Drawn type1_reports(int n, unsigned seed = 1) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> b1(0.424, 0.01), b2(-0.2, 0.03), p95(0.1, 0.005);
  Drawn d;
  for (int k = 0; k < n; ++k) {
    d.bend1.push_back(b1(rng));
    d.bend2.push_back(b2(rng));
    d.reports.push_back(make_report(k, "REF-1", d.bend1.back(), d.bend2.back(), p95(rng)));
  }
  return d;
}

/// The test's own mean and s (n - 1).
std::pair<double, double> mean_and_s(const std::vector<double>& x) {
  long double sum = 0, sum2 = 0;
  for (const double v : x) sum += v, sum2 += static_cast<long double>(v) * v;
  const long double n = static_cast<long double>(x.size());
  return {static_cast<double>(sum / n),
          static_cast<double>(std::sqrt((sum2 - sum * sum / n) / (n - 1)))};
}

const std::map<std::string, double> kReferences = {{"bend 1 springback", 0.42},
                                                   {"bend 2 springback", -0.2}};

TEST(MsaStudies, Type1FiguresFromDrawnReports) {
  const Drawn d = type1_reports(50);
  auto study = type1_study(d.reports, kReferences);
  ASSERT_TRUE(study.ok()) << study.message();
  EXPECT_EQ(study->part_id(), "7");
  EXPECT_EQ(study->reports(), 50);
  ASSERT_EQ(study->characteristics_size(), 2);
  const auto& c1 = study->characteristics(0);
  EXPECT_EQ(c1.name(), "bend 1 springback");
  EXPECT_EQ(c1.unit(), "deg");
  EXPECT_DOUBLE_EQ(c1.tolerance(), 1.0);  // 2 x 0.5 deg
  const auto [m1, s1] = mean_and_s(d.bend1);
  EXPECT_NEAR(c1.mean(), m1, 1e-12);
  EXPECT_NEAR(c1.stddev(), s1, 1e-9);
  EXPECT_NEAR(c1.bias(), m1 - 0.42, 1e-12);
  EXPECT_NEAR(c1.cg(), 0.2 * 1.0 / (6 * s1), 1e-6);
  EXPECT_NEAR(c1.cgk(), (0.1 - std::abs(m1 - 0.42)) / (3 * s1), 1e-6);
  // Truth: sigma 0.01 gives Cg 3.33, Cgk (0.1 - 0.004) / 0.03 = 3.2: capable; the 0.4 sigma
  // bias is found by the t-test at n = 50 (power ~ 0.5), so that is not checked.
  EXPECT_TRUE(c1.capable());
  EXPECT_EQ(c1.values_size(), 50);
  // Bend 2 at sigma 0.03: Cg = 0.2 / 0.18 = 1.11 < 1.33 in truth; not capable.
  const auto& c2 = study->characteristics(1);
  EXPECT_NEAR(c2.cg(), 0.2 / (6 * mean_and_s(d.bend2).second), 1e-6);
  EXPECT_FALSE(c2.capable());
  EXPECT_FALSE(study->capable());
}

TEST(MsaStudies, Type1ToleranceOverrideAndOnly) {
  const Drawn d = type1_reports(30);
  MsaSettings settings;
  settings.tolerances["bend 2 springback"] = 4.0;
  settings.only = {"bend 2 springback"};
  auto study = type1_study(d.reports, kReferences, settings);
  ASSERT_TRUE(study.ok()) << study.message();
  ASSERT_EQ(study->characteristics_size(), 1);
  EXPECT_DOUBLE_EQ(study->characteristics(0).tolerance(), 4.0);
  EXPECT_NEAR(study->characteristics(0).cg(), 0.8 / (6 * mean_and_s(d.bend2).second), 1e-6);
}

TEST(MsaStudies, Type1Refusals) {
  EXPECT_FALSE(type1_study(type1_reports(24).reports, kReferences).ok());  // too few
  Drawn mixed = type1_reports(30);
  mixed.reports[3].mutable_input()->set_part_id("8");
  auto m = type1_study(mixed.reports, kReferences);
  ASSERT_FALSE(m.ok());
  EXPECT_NE(m.message().find("mixed part ids"), std::string::npos) << m.message();
  Drawn missing = type1_reports(30);
  missing.reports[5] = make_report(5, "REF-1", 0.42, NAN, 0.1);  // bend 2 not measured
  auto g = type1_study(missing.reports, kReferences);
  ASSERT_FALSE(g.ok());
  EXPECT_NE(g.message().find("'bend 2 springback' is missing in 1 of 30"), std::string::npos)
      << g.message();
  auto unknown = type1_study(type1_reports(30).reports, {{"bend 9 springback", 0.0}});
  ASSERT_FALSE(unknown.ok());
  EXPECT_NE(unknown.message().find("in none of the reports"), std::string::npos);
}

struct Drawn3 {
  std::vector<v1::InspectionReport> reports;
  std::vector<std::vector<double>> bend1;  ///< [part][trial]
};

/// `parts` parts with true springback N(0.4, 0.05), each measured `trials` times with
/// N(0, 0.008) repeat error; the trials come round by round (part 1..p, then again).
Drawn3 type3_reports(int parts, int trials) {
  std::mt19937 rng(11);
  std::normal_distribution<double> part(0.4, 0.05), repeat(0.0, 0.008);
  std::vector<double> truth;
  for (int i = 0; i < parts; ++i) truth.push_back(part(rng));
  Drawn3 d;
  d.bend1.resize(static_cast<std::size_t>(parts));
  int seq = 0;
  for (int t = 0; t < trials; ++t)
    for (int i = 0; i < parts; ++i) {
      const double b1 = truth[static_cast<std::size_t>(i)] + repeat(rng);
      d.bend1[static_cast<std::size_t>(i)].push_back(b1);
      d.reports.push_back(make_report(seq++, std::string("S").append(std::to_string(100 + i)), b1,
                                      -0.1 + repeat(rng), 0.1));
    }
  return d;
}

TEST(MsaStudies, Type3FiguresFromDrawnReports) {
  const Drawn3 d = type3_reports(10, 3);
  auto study = type3_study(d.reports);
  ASSERT_TRUE(study.ok()) << study.message();
  // bend 1, bend 2, deviation max |d|, deviation p95 (sorted by name).
  ASSERT_EQ(study->characteristics_size(), 4);
  const v1::MsaType3Characteristic& c = study->characteristics(0);
  ASSERT_EQ(c.name(), "bend 1 springback");
  EXPECT_EQ(c.parts(), 10);
  EXPECT_EQ(c.trials(), 3);
  EXPECT_EQ(c.part_serials(0), "S100");
  // The test's own ANOVA: pooled within-part variance, variance of the part means.
  double within = 0.0, means_ss = 0.0, grand = 0.0;
  std::vector<double> means;
  for (const auto& trials : d.bend1) {
    const auto [m, s] = mean_and_s(trials);
    within += s * s;
    means.push_back(m);
    grand += m / 10.0;
  }
  for (const double m : means) means_ss += (m - grand) * (m - grand);
  const double ms_within = within / 10.0, ms_parts = 3.0 * means_ss / 9.0;
  const double ev = std::sqrt(ms_within), pv = std::sqrt((ms_parts - ms_within) / 3.0);
  EXPECT_NEAR(c.ev(), ev, 1e-9);
  EXPECT_NEAR(c.pv(), pv, 1e-9);
  EXPECT_NEAR(c.grr(), ev, 1e-9);
  EXPECT_NEAR(c.grr_pct_tolerance(), 100.0 * 6.0 * ev / 1.0, 1e-6);
  EXPECT_NEAR(c.grr_pct_total(), 100.0 * ev / std::hypot(ev, pv), 1e-6);
  EXPECT_NEAR(c.ndc(), 1.41 * pv / ev, 1e-6);
  // Truth: %GRR of T = 600 * 0.008 = 4.8 %, ndc = 1.41 * 0.05 / 0.008 = 8.8.
  EXPECT_EQ(c.verdict(), "acceptable");
  EXPECT_TRUE(c.acceptable());
  EXPECT_EQ(c.values_size(), 30);
  EXPECT_EQ(c.values(1), d.bend1[0][1]);
}

TEST(MsaStudies, Type3Refusals) {
  EXPECT_FALSE(type3_study(type3_reports(4, 3).reports).ok());  // 4 parts
  EXPECT_FALSE(type3_study(type3_reports(5, 1).reports).ok());  // 1 trial
  Drawn3 unbalanced = type3_reports(5, 3);
  unbalanced.reports.pop_back();
  auto u = type3_study(unbalanced.reports);
  ASSERT_FALSE(u.ok());
  EXPECT_NE(u.message().find("unbalanced study"), std::string::npos) << u.message();
  Drawn3 no_serial = type3_reports(5, 2);
  no_serial.reports[2].mutable_input()->clear_part_serial();
  auto n = type3_study(no_serial.reports);
  ASSERT_FALSE(n.ok());
  EXPECT_NE(n.message().find("no input.part_serial"), std::string::npos);
  Drawn3 missing = type3_reports(5, 2);
  missing.reports[4] = make_report(4, "S104", NAN, 0.1, 0.1);
  EXPECT_FALSE(type3_study(missing.reports).ok());
  MsaSettings only;  // ... unless that characteristic is left out
  only.only = {"bend 2 springback"};
  EXPECT_TRUE(type3_study(missing.reports, only).ok());
}

TEST(MsaStudies, ReferencesAndToleranceArguments) {
  auto refs = parse_references(R"({"bend 1 springback": 0.42, "deviation p95": 0.1})");
  ASSERT_TRUE(refs.ok()) << refs.message();
  EXPECT_EQ(refs->at("bend 1 springback"), 0.42);
  EXPECT_FALSE(parse_references(R"({"bend 1 springback": "x"})").ok());
  EXPECT_FALSE(parse_references("[1, 2]").ok());
  auto t = parse_tolerance("bend 1 springback=1.5");
  ASSERT_TRUE(t.ok());
  EXPECT_EQ(t->first, "bend 1 springback");
  EXPECT_EQ(t->second, 1.5);
  EXPECT_FALSE(parse_tolerance("bend 1 springback").ok());
  EXPECT_FALSE(parse_tolerance("bend 1 springback=-1").ok());
  EXPECT_FALSE(parse_tolerance("bend 1 springback=1x").ok());
}

TEST(MsaStudies, PagesHaveTheTableAndTheCharts) {
  auto t1 = type1_study(type1_reports(25).reports, kReferences);
  ASSERT_TRUE(t1.ok());
  MsaPageInfo info;
  info.sources = {"store <A&B>"};
  const std::string html = render_type1_html(*t1, info);
  const auto count = [](const std::string& text, const std::string& what) {
    std::size_t n = 0;
    for (auto at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
    return n;
  };
  EXPECT_EQ(count(html, "<tr class=\"characteristic\">"), 2u);
  EXPECT_EQ(count(html, "<svg class=\"run-chart\""), 2u);
  EXPECT_EQ(count(html, "<svg class=\"histogram\""), 2u);
  EXPECT_EQ(count(html, "<circle class=\"value\""), 50u);
  EXPECT_NE(html.find("store &lt;A&amp;B&gt;"), std::string::npos);
  EXPECT_EQ(html.find("<script"), std::string::npos);
  auto t3 = type3_study(type3_reports(5, 2).reports);
  ASSERT_TRUE(t3.ok());
  const std::string page3 = render_type3_html(*t3, info);
  EXPECT_EQ(count(page3, "<svg class=\"parts-chart\""), 4u);
  EXPECT_EQ(count(page3, "<circle class=\"value\""), 4u * 10u);
}

// ---- springscan msa, end to end --------------------------------------------------------------

class MsaCli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("springscan_msa_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  void write_store(const std::string& name, const std::vector<v1::InspectionReport>& reports) {
    for (std::size_t k = 0; k < reports.size(); ++k) {
      const fs::path folder = dir_ / name / std::string("r").append(std::to_string(1000 + k));
      fs::create_directories(folder);
      std::ofstream(folder / "report.pb", std::ios::binary) << reports[k].SerializeAsString();
    }
  }
  int run(const std::string& arguments) {
    const std::string command = std::string(test_paths::kSpringscan) + " msa " + arguments + " > " +
                                (dir_ / "out.txt").string() + " 2> " + (dir_ / "err.txt").string();
    const int status = std::system(command.c_str());
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  }
  std::string read(const fs::path& path) {
    std::ifstream in(path);
    std::stringstream text;
    text << in.rdbuf();
    return text.str();
  }
  fs::path dir_;
};

TEST_F(MsaCli, Type1WritesThePageAndTheJson) {
  const Drawn d = type1_reports(30);
  write_store("store", d.reports);
  std::ofstream(dir_ / "ref.json") << R"({"bend 1 springback": 0.42})";
  const std::string args = "type1 " + (dir_ / "store").string() + " --reference " +
                           (dir_ / "ref.json").string() + " --out " + (dir_ / "msa.html").string() +
                           " --json " + (dir_ / "msa.json").string() +
                           " --tolerance 'bend 1 springback=0.8'";
  ASSERT_EQ(run(args), 0) << read(dir_ / "err.txt");
  v1::MsaType1Study study;
  ASSERT_TRUE(google::protobuf::util::JsonStringToMessage(read(dir_ / "msa.json"), &study).ok());
  ASSERT_EQ(study.characteristics_size(), 1);
  const auto [m, s] = mean_and_s(d.bend1);
  EXPECT_NEAR(study.characteristics(0).cg(), 0.2 * 0.8 / (6 * s), 1e-6);
  EXPECT_NEAR(study.characteristics(0).cgk(), (0.08 - std::abs(m - 0.42)) / (3 * s), 1e-6);
  for (const char* field : {"\"name\"", "\"unit\"", "\"tolerance\"", "\"n\"", "\"mean\"",
                            "\"stddev\"", "\"bias\"", "\"cg\"", "\"cgk\""})
    EXPECT_NE(read(dir_ / "msa.json").find(field), std::string::npos) << field;
  EXPECT_NE(read(dir_ / "msa.html").find("<svg class=\"histogram\""), std::string::npos);
  EXPECT_NE(read(dir_ / "out.txt").find("bend 1 springback: n 30"), std::string::npos);
}

TEST_F(MsaCli, RefusalsWriteNothing) {
  write_store("few", type1_reports(10).reports);
  std::ofstream(dir_ / "ref.json") << R"({"bend 1 springback": 0.42})";
  const std::string outs =
      " --out " + (dir_ / "msa.html").string() + " --json " + (dir_ / "msa.json").string();
  EXPECT_EQ(run("type1 " + (dir_ / "few").string() + " --reference " +
                (dir_ / "ref.json").string() + outs),
            1);
  EXPECT_NE(read(dir_ / "err.txt").find("at least 25 reports"), std::string::npos);
  Drawn3 unbalanced = type3_reports(5, 2);
  unbalanced.reports.pop_back();
  write_store("unbalanced", unbalanced.reports);
  EXPECT_EQ(run("type3 " + (dir_ / "unbalanced").string() + outs), 1);
  EXPECT_NE(read(dir_ / "err.txt").find("unbalanced study"), std::string::npos);
  EXPECT_EQ(run("type1 " + (dir_ / "few").string() + outs), 2);  // no --reference
  EXPECT_EQ(run("type2 " + (dir_ / "few").string() + outs), 2);
  EXPECT_FALSE(fs::exists(dir_ / "msa.html"));
  EXPECT_FALSE(fs::exists(dir_ / "msa.json"));
  // The balanced study goes through.
  write_store("balanced", type3_reports(5, 2).reports);
  EXPECT_EQ(run("type3 " + (dir_ / "balanced").string() + outs), 0) << read(dir_ / "err.txt");
  EXPECT_TRUE(fs::exists(dir_ / "msa.json"));
}

}  // namespace
}  // namespace springscan::report
