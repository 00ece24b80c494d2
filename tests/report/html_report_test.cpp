// The HTML report's structure: verdict, bend rows, escaping, no network references, embedded
// pictures that decode, and the writer.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <regex>
#include <sstream>

#include "report/figures.hpp"
#include "report/html_text.hpp"
#include "report/plots.hpp"
#include "report/report_html.hpp"
#include "tests/report/png_decode.hpp"
#include "tests/report/report_fixture.hpp"

namespace springscan::report {
namespace {

std::size_t count_of(const std::string& text, const std::string& what) {
  std::size_t n = 0;
  for (auto at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

// The text of the table row with id `bend-<id>`.
std::string bend_row(const std::string& html, int id) {
  const auto at = html.find("id='bend-" + std::to_string(id) + "'");
  if (at == std::string::npos) return "";
  return html.substr(at, html.find("</tr>", at) - at);
}

class HtmlReport : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    fixture_ = new testing::Fixture(testing::make_fixture(20'000));
    auto html = render_report_html(fixture_->report, fixture_->cloud);
    ASSERT_TRUE(html.ok()) << html.message();
    html_ = new std::string(*html);
  }
  static void TearDownTestSuite() {
    delete fixture_;
    delete html_;
  }
  static testing::Fixture* fixture_;
  static std::string* html_;
};
testing::Fixture* HtmlReport::fixture_ = nullptr;
std::string* HtmlReport::html_ = nullptr;

TEST_F(HtmlReport, StartsWithTheVerdictAndItsReasons) {
  const auto banner = html_->find("class='banner fail'");
  ASSERT_NE(banner, std::string::npos);
  EXPECT_LT(banner, html_->find("id='deviation'"));  // at the top, before any section
  EXPECT_NE(html_->find(">FAIL<", banner), std::string::npos);
  EXPECT_NE(html_->find("bend B2 springback +2.40\u00b0 exceeds"), std::string::npos);
  EXPECT_EQ(html_->find("class='banner pass'"), std::string::npos);
}

TEST_F(HtmlReport, HasOneRowPerBendWithItsNumbersAndResult) {
  EXPECT_EQ(count_of(*html_, "<tr class='bend "), 4u);
  const std::string b1 = bend_row(*html_, 1), b2 = bend_row(*html_, 2), b4 = bend_row(*html_, 4);
  EXPECT_NE(b1.find(">89.60<"), std::string::npos) << b1;  // measured = 90 - 0.4
  EXPECT_NE(b1.find(">+0.40<"), std::string::npos) << b1;
  EXPECT_NE(b1.find(">PASS<"), std::string::npos) << b1;
  EXPECT_NE(b2.find(">87.60<"), std::string::npos) << b2;
  EXPECT_NE(b2.find(">FAIL<"), std::string::npos) << b2;
  EXPECT_NE(b4.find(">NOT MEASURED<"), std::string::npos) << b4;
  // Each bend is labelled on the picture.
  for (int id = 1; id <= 4; ++id)
    EXPECT_NE(html_->find(">B" + std::to_string(id) + "</text>"), std::string::npos) << id;
}

TEST_F(HtmlReport, ShowsTheAngleAlongTheBendAndTheFlangeShape) {
  const std::string b2 = bend_row(*html_, 2), b1 = bend_row(*html_, 1), b3 = bend_row(*html_, 3);
  EXPECT_NE(b2.find(">87.30 &ndash; 87.90<br>spread 0.60 <svg class='spark'"), std::string::npos)
      << b2;
  EXPECT_NE(b2.find("<polyline"), std::string::npos) << b2;
  EXPECT_NE(b2.find(">4.07<"), std::string::npos) << b2;  // measured radius
  EXPECT_NE(b1.find("<td class='num'>&mdash;</td>"), std::string::npos) << "no stations: " << b1;
  EXPECT_NE(b3.find("&dagger;"), std::string::npos) << b3;  // end-tangent angle
  EXPECT_EQ(b2.find("&dagger;"), std::string::npos) << b2;
  // The flange table: flatness with its rms, curl ("flat" when none), twist.
  EXPECT_NE(html_->find(">1.234 (rms 0.020)</td><td class='num'>-240</td><td class='num'>+0.125<"),
            std::string::npos);
  EXPECT_NE(html_->find(">0.081 (rms 0.020)</td><td class='num'>flat</td>"), std::string::npos);
  EXPECT_NE(html_->find(">free edge: in-plane +0.31 (+0.29 to +0.33), across -0.52 (-0.55 to "
                        "-0.49)<"),
            std::string::npos);
  EXPECT_NE(html_->find(">side edge: in-plane -0.12 (-0.15 to -0.10), across +0.04 (+0.03 to "
                        "+0.05)<"),
            std::string::npos);
}

// The fixture's two measured trim edges (a free edge, a side edge), drawn on each of the four
// deviation views: the CAD edge and the scan's edge, three strip centres each.
TEST_F(HtmlReport, DrawsTheTrimEdgesOnEveryDeviationView) {
  const auto section = html_->substr(html_->find("<section id='deviation'>"));
  const std::string deviation = section.substr(0, section.find("</section>"));
  const auto count = [&](const std::string& needle) {
    std::size_t n = 0;
    for (auto at = deviation.find(needle); at != std::string::npos;
         at = deviation.find(needle, at + 1))
      ++n;
    return n;
  };
  EXPECT_EQ(count("<polyline class='cadedge' points='"), 8u);
  EXPECT_EQ(count("<polyline class='scanedge' points='"), 8u);
  const auto at = deviation.find("<polyline class='scanedge' points='");
  const std::string points = deviation.substr(at, deviation.find("'/>", at) - at);
  EXPECT_EQ(std::count(points.begin(), points.end(), ','), 3) << points;
}

TEST_F(HtmlReport, EscapesEveryTextFromTheReport) {
  EXPECT_NE(html_->find("HAT-7 &lt;rev&amp;B&gt;"), std::string::npos);
  EXPECT_EQ(html_->find("HAT-7 <rev"), std::string::npos);
  EXPECT_NE(html_->find("press-line-3 &lt;cell &quot;A&quot;&gt;"), std::string::npos);
  EXPECT_EQ(html_->find("<cell"), std::string::npos);
}

TEST_F(HtmlReport, IsSelfContained) {
  EXPECT_EQ(html_->find("http://"), std::string::npos);
  EXPECT_EQ(html_->find("https://"), std::string::npos);
  EXPECT_EQ(html_->find("<script"), std::string::npos);
  EXPECT_EQ(html_->find("<link"), std::string::npos);
  EXPECT_EQ(html_->find("url(http"), std::string::npos);
  // Every picture is a data: URI: 4 deviation views, the bends, the compensation arrows.
  EXPECT_EQ(count_of(*html_, "href='data:image/png;base64,"), 6u);
  EXPECT_NE(html_->find("@page"), std::string::npos);
}

TEST_F(HtmlReport, EmbeddedViewsDecodeAndShowThePart) {
  const std::string key = "href='data:image/png;base64,";
  const auto at = html_->find(key) + key.size();
  const std::string b64 = html_->substr(at, html_->find('\'', at) - at);
  // Decode base64 by hand (the inverse of report::base64).
  std::string bytes;
  int bits = 0, value = 0;
  for (char c : b64) {
    const auto pos =
        std::string("ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/").find(c);
    if (pos == std::string::npos) break;
    value = (value << 6) | static_cast<int>(pos);
    if ((bits += 6) >= 8) bytes.push_back(static_cast<char>((value >> (bits -= 8)) & 0xff));
  }
  auto png = testing::decode_png(bytes);
  ASSERT_TRUE(png);
  EXPECT_EQ(png->width, ReportSettings{}.view_width_px);
  std::size_t coloured = 0;
  for (std::size_t i = 0; i < png->pixels.size(); i += 3)
    coloured += (png->pixels[i] != 255 || png->pixels[i + 1] != 255) ? 1 : 0;
  // The top view of the hat profile fills most of its frame.
  EXPECT_GT(coloured, png->pixels.size() / 3 / 2);
}

TEST_F(HtmlReport, PlotsTheErrorProgression) {
  // 9 errors: 9 dots of E(i), 8 of the quotient.
  EXPECT_EQ(count_of(*html_, "<circle class='s1'"), 9u);
  EXPECT_EQ(count_of(*html_, "<circle class='s2'"), 8u);
  EXPECT_NE(html_->find("stop 0.995"), std::string::npos);
}

TEST(HtmlReportAlone, PassingReportWithoutCloudSaysThePictureIsMissing) {
  auto f = testing::make_fixture(0);
  f.report.mutable_verdict()->set_pass(true);
  f.report.mutable_verdict()->clear_reasons();
  ReportSettings settings;
  settings.missing_cloud_note = "deviation.ply not found beside report.pb";
  auto html = render_report_html(f.report, {}, settings);
  ASSERT_TRUE(html.ok()) << html.message();
  EXPECT_NE(html->find("class='banner pass'"), std::string::npos);
  EXPECT_NE(html->find("Picture missing: deviation.ply not found beside report.pb"),
            std::string::npos);
  EXPECT_EQ(count_of(*html, "<tr class='bend "), 4u);
  // Compensation arrows still draw, on their own.
  EXPECT_NE(html->find("class='arrow'"), std::string::npos);
}

// An UNDECIDED report: its own banner and word, the rule that decided, each value with its U,
// each bend's decision (issue 41).
TEST(HtmlReportAlone, UndecidedShowsValuesWithTheirUAndEachDecision) {
  auto f = testing::make_fixture(0);
  v1::Verdict* verdict = f.report.mutable_verdict();
  verdict->set_pass(false);
  verdict->set_decision(v1::Verdict::UNDECIDED);
  verdict->set_decision_rule(v1::VerdictSettings::GUARD_BAND);
  v1::Bend* b1 = f.report.mutable_bends(0);
  b1->set_springback_uncertainty_deg(0.125);
  b1->set_angle_uncertainty_deg(0.25);
  b1->set_decision(v1::UNDECIDED);
  f.report.mutable_bends(1)->set_decision(v1::NONCONFORMING);
  f.report.mutable_deviation()->set_uncertainty_mm(0.03);
  f.report.mutable_deviation()->set_decision(v1::CONFORMING);
  auto html = render_report_html(f.report, {});
  ASSERT_TRUE(html.ok()) << html.message();
  EXPECT_NE(html->find("class='banner undecided'"), std::string::npos);
  EXPECT_NE(html->find("<div class='word'>UNDECIDED</div>"), std::string::npos);
  EXPECT_NE(html->find("Decided by the guard band (ISO 14253-1)"), std::string::npos);
  const std::string row1 = bend_row(*html, b1->id());
  EXPECT_NE(html->find("<tr class='bend ud' id='bend-" + std::to_string(b1->id()) + "'"),
            std::string::npos);
  EXPECT_NE(row1.find(">89.60 &plusmn; 0.250"), std::string::npos) << row1;
  EXPECT_NE(row1.find(">+0.40 &plusmn; 0.125<"), std::string::npos) << row1;
  EXPECT_NE(row1.find(">UNDECIDED<"), std::string::npos) << row1;
  EXPECT_NE(bend_row(*html, f.report.bends(1).id()).find(">FAIL<"), std::string::npos);
  EXPECT_NE(html->find("U of the statistic judged (k = 2)</td><td class='num'>0.030 mm"),
            std::string::npos);
  EXPECT_NE(html->find("Surface criterion</td><td class='num'>CONFORMING"), std::string::npos);
  // SIMPLE says so.
  verdict->set_decision(v1::Verdict::PASS);
  verdict->set_pass(true);
  verdict->set_decision_rule(v1::VerdictSettings::SIMPLE);
  html = render_report_html(f.report, {});
  ASSERT_TRUE(html.ok());
  EXPECT_NE(html->find("class='banner pass'"), std::string::npos);
  EXPECT_NE(html->find("Decided by the simple rule"), std::string::npos);
}

// A trim edge's U (issue 41): in plane and across each its own; a report written before they
// were split shows its one U.
TEST(HtmlReportAlone, ShowsEachEdgeMovesOwnU) {
  auto f = testing::make_fixture(0);
  v1::EdgeDeviation* edge = f.report.mutable_segments(0)->mutable_trim_edges(0);
  edge->set_uncertainty_mm(0.3);
  auto html = render_report_html(f.report, {});
  ASSERT_TRUE(html.ok()) << html.message();
  EXPECT_NE(html->find("across -0.52 (-0.55 to -0.49), U 0.30<"), std::string::npos);
  edge->set_in_plane_uncertainty_mm(0.3);
  edge->set_across_uncertainty_mm(0.04);
  html = render_report_html(f.report, {});
  ASSERT_TRUE(html.ok()) << html.message();
  EXPECT_NE(html->find("across -0.52 (-0.55 to -0.49), U 0.30 in-plane, 0.04 across<"),
            std::string::npos);
}

// The result frame's U beside the global fit's figures (issue 41): rotation and translation, each
// with its unit; n/a where the report has none.
TEST(HtmlReportAlone, ShowsTheResultFramesUncertainty) {
  auto f = testing::make_fixture(0);
  auto html = render_report_html(f.report, {});
  ASSERT_TRUE(html.ok()) << html.message();
  EXPECT_NE(html->find("Result frame U rotation (k = 2)</td><td class='num'>n/a"),
            std::string::npos);
  v1::Alignment* a = f.report.mutable_alignment();
  a->set_method("datum");
  a->set_achieved(true);
  a->set_uncertainty_rotation_deg(0.0126);
  a->set_uncertainty_translation_mm(0.25);
  html = render_report_html(f.report, {});
  ASSERT_TRUE(html.ok()) << html.message();
  EXPECT_NE(html->find("Result frame</td><td class='num'>datum<"), std::string::npos);
  EXPECT_NE(html->find("Result frame U rotation (k = 2)</td><td class='num'>\u00b1 0.013\u00b0"),
            std::string::npos);
  EXPECT_NE(html->find("Result frame U translation (k = 2)</td><td class='num'>\u00b1 0.250 mm"),
            std::string::npos);
  a->set_method("best_fit");
  a->set_achieved(false);
  a->set_failure("datum A not measurable");
  html = render_report_html(f.report, {});
  ASSERT_TRUE(html.ok()) << html.message();
  EXPECT_NE(html->find("Result frame</td><td class='num'>best_fit (datum frame not achieved)<"),
            std::string::npos);
}

// The compensation arrows read against the deviation map: haloed, at a round drawing scale, with
// a key arrow whose drawn length is to scale. The fixture's vectors lie in the section plane (the
// view the figure picks), the longest 0.6 * sin(2 pi 14.5 / 60) = 0.599 mm long.
TEST_F(HtmlReport, CompensationArrowsAreToAStatedRoundScaleWithAKey) {
  const auto at = html_->find("id='compensation'");
  ASSERT_NE(at, std::string::npos);
  const std::string section = html_->substr(at, html_->find("</section>", at) - at);
  const std::regex line_re(
      "<line class='(arrow|halo)' x1='([-0-9.]+)' y1='([-0-9.]+)' x2='([-0-9.]+)' "
      "y2='([-0-9.]+)'");
  std::vector<double> arrows, halos;
  for (std::sregex_iterator it(section.begin(), section.end(), line_re), end; it != end; ++it) {
    const auto& m = *it;
    const double length =
        std::hypot(std::stod(m[4]) - std::stod(m[2]), std::stod(m[5]) - std::stod(m[3]));
    (m[1] == "arrow" ? arrows : halos).push_back(length);
  }
  ASSERT_GT(arrows.size(), 10u);
  EXPECT_EQ(halos, arrows);  // every arrow on its halo
  // The key is drawn last, in its group, labelled with a round length.
  const auto key = section.find("<g class='key'>");
  ASSERT_NE(key, std::string::npos);
  EXPECT_NE(section.find(">0.2 mm</text>", key), std::string::npos);
  const double key_px = arrows.back();
  arrows.pop_back();
  const double longest_px = *std::max_element(arrows.begin(), arrows.end());
  EXPECT_NEAR(key_px / longest_px, 0.2 / (0.6 * std::sin(2 * std::numbers::pi * 14.5 / 60)), 0.01);
  // The drawing scale in the caption is 1, 2 or 5 x 10^k.
  std::smatch gain;
  ASSERT_TRUE(std::regex_search(section, gain, std::regex("arrows drawn ([0-9.]+) \u00d7")));
  const double g = std::stod(gain[1]);
  const double mantissa = g / std::pow(10.0, std::floor(std::log10(g)));
  EXPECT_TRUE(std::abs(mantissa - 1) < 1e-9 || std::abs(mantissa - 2) < 1e-9 ||
              std::abs(mantissa - 5) < 1e-9)
      << g;
  EXPECT_NE(section.find("on the deviation map"), std::string::npos);
}

TEST(HtmlReportAlone, RejectsACloudWithMismatchedAttributes) {
  analysis::PointCloud cloud;
  cloud.points = {{0, 0, 0}, {1, 0, 0}};
  cloud.scalars = {0.1};
  auto html = render_report_html(v1::InspectionReport{}, cloud);
  ASSERT_FALSE(html.ok());
  EXPECT_NE(html.message().find("2 points"), std::string::npos) << html.message();
}

TEST(HtmlReportAlone, EmptyReportStillRenders) {
  auto html = render_report_html(v1::InspectionReport{}, {});
  ASSERT_TRUE(html.ok()) << html.message();
  EXPECT_NE(html->find("No error history"), std::string::npos);
  EXPECT_NE(html->find("No bends"), std::string::npos);
}

TEST(HtmlReportAlone, WriterPutsTheFileInPlaceOrNamesThePath) {
  const auto dir = std::filesystem::temp_directory_path() / "springscan_report_writer_test";
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  const auto f = testing::make_fixture(2000);
  auto written = write_report_html_in_dir(dir, f.report, f.cloud);
  ASSERT_TRUE(written.ok()) << written.message();
  EXPECT_EQ(*written, dir / "report.html");
  std::ifstream in(*written, std::ios::binary);
  std::stringstream content;
  content << in.rdbuf();
  EXPECT_EQ(content.str(), *render_report_html(f.report, f.cloud));  // same seed, same bytes
  EXPECT_EQ(std::distance(std::filesystem::directory_iterator(dir),
                          std::filesystem::directory_iterator()),
            1);  // no temporary file left behind
  auto missing = write_report_html_in_dir(dir / "no" / "such", f.report, f.cloud);
  ASSERT_FALSE(missing.ok());
  EXPECT_NE(missing.message().find("no/such"), std::string::npos) << missing.message();
  std::filesystem::remove_all(dir);
}

TEST(HtmlReportAlone, SamePageForAnyThreadCount) {
  const auto f = testing::make_fixture(3000);
  ReportSettings one, many;
  one.threads = 1;
  many.threads = 3;
  EXPECT_EQ(*render_report_html(f.report, f.cloud, one),
            *render_report_html(f.report, f.cloud, many));
}

TEST(HtmlText, EscapesAndEncodes) {
  EXPECT_EQ(escape_html("<a href=\"x\">Tom & 'Jerry'</a>"),
            "&lt;a href=&quot;x&quot;&gt;Tom &amp; &#39;Jerry&#39;&lt;/a&gt;");
  EXPECT_EQ(base64(""), "");
  EXPECT_EQ(base64("f"), "Zg==");
  EXPECT_EQ(base64("fo"), "Zm8=");
  EXPECT_EQ(base64("foobar"), "Zm9vYmFy");  // RFC 4648 section 10
  EXPECT_EQ(fixed(-0.0001, 2), "0.00");
  EXPECT_EQ(signed_fixed(0.4, 2), "+0.40");
  EXPECT_EQ(signed_fixed(-0.3, 2), "-0.30");
  EXPECT_EQ(signed_fixed(0.0, 2), "0.00");
  EXPECT_EQ(fixed(std::nan(""), 2), "n/a");
}

TEST(Plots, NiceStepsAndColourBarTolerance) {
  EXPECT_DOUBLE_EQ(nice_step(10.0, 5), 2.0);
  EXPECT_DOUBLE_EQ(nice_step(2.0, 8), 0.2);
  EXPECT_DOUBLE_EQ(nice_step(0.0, 5), 1.0);
  const std::string bar = color_bar_svg(1.0, 0.5, 500);
  EXPECT_EQ(count_of(bar, "class='tol'"), 2u);
  EXPECT_NE(bar.find("\u00b10.500 mm"), std::string::npos);
  EXPECT_NE(bar.find(">-1.0<"), std::string::npos);
  EXPECT_NE(bar.find(">+1.0<"), std::string::npos);
}

TEST(Figures, BendAxisSpansThePointsNearIt) {
  v1::Bend bend;
  bend.mutable_axis_point()->set_x(10);
  bend.mutable_axis_point()->set_y(40);
  bend.mutable_axis_direction()->set_y(2);  // not unit: normalised inside
  bend.set_radius_mm(2);
  std::vector<Vec3> points;
  for (int y = 0; y <= 80; ++y) points.emplace_back(10.5, y, 0.5);  // along the axis
  for (int x = 30; x <= 130; ++x) points.emplace_back(x, 200, 0);   // far away
  const auto [a, b] = bend_axis_extent(bend, points);
  EXPECT_TRUE(a.isApprox(Vec3(10, 0, 0))) << a.transpose();
  EXPECT_TRUE(b.isApprox(Vec3(10, 80, 0))) << b.transpose();
}

}  // namespace
}  // namespace springscan::report
