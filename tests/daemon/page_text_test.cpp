// What the operator page says (daemon/page_text.hpp): verdict and state words, the fault in
// words, the shift's bounds and counts, and the deviation picture taken from report.html.
#include "daemon/page_text.hpp"

#include <gtest/gtest.h>

namespace springscan::daemon {
namespace {

std::time_t local(int year, int month, int day, int hour, int minute) {
  std::tm tm{};
  tm.tm_year = year - 1900;
  tm.tm_mon = month - 1;
  tm.tm_mday = day;
  tm.tm_hour = hour;
  tm.tm_min = minute;
  tm.tm_isdst = -1;
  return std::mktime(&tm);
}

v1::InspectionReport report(std::uint32_t seq, regs::ResultCode code) {
  v1::InspectionReport r;
  r.set_result_seq(seq);
  r.set_result_code(static_cast<std::uint32_t>(code));
  r.mutable_verdict()->set_pass(code == regs::ResultCode::kOk);
  return r;
}

TEST(PageText, VerdictAndStateWords) {
  EXPECT_STREQ(page_verdict(report(1, regs::ResultCode::kOk)), "PASS");
  EXPECT_STREQ(page_verdict(report(1, regs::ResultCode::kFormNok)), "FAIL");
  EXPECT_STREQ(page_verdict(report(1, regs::ResultCode::kAmbiguous)), "FAIL");
  EXPECT_STREQ(page_verdict(report(1, regs::ResultCode::kScanFailed)), "NO RESULT");
  EXPECT_STREQ(page_verdict(report(1, regs::ResultCode::kAnalysisFailed)), "NO RESULT");
  v1::InspectionReport offline;  // `springscan analyze` sets no RESULT_CODE: the verdict decides
  offline.mutable_verdict()->set_pass(false);
  EXPECT_STREQ(page_verdict(offline), "FAIL");
  offline.mutable_verdict()->set_pass(true);
  EXPECT_STREQ(page_verdict(offline), "PASS");
  // UNDECIDED: RESULT_CODE 6, or an offline report whose decision says so; never PASS.
  EXPECT_STREQ(page_verdict(report(1, regs::ResultCode::kUndecided)), "UNDECIDED");
  offline.mutable_verdict()->set_pass(false);
  offline.mutable_verdict()->set_decision(v1::Verdict::UNDECIDED);
  EXPECT_STREQ(page_verdict(offline), "UNDECIDED");
  EXPECT_STREQ(page_state(regs::State::kIdle), "idle");
  EXPECT_STREQ(page_state(regs::State::kAcquiring), "scanning");
  EXPECT_STREQ(page_state(regs::State::kAnalyzing), "analysing");
  EXPECT_STREQ(page_state(regs::State::kFault), "fault");
  EXPECT_EQ(fault_text(regs::ErrorCode::kNone, regs::ErrorDetail::kNone), "");
  EXPECT_EQ(fault_text(regs::ErrorCode::kScanFailed, regs::ErrorDetail::kDeviceGone)
                .rfind("ERROR 2: scan failed", 0),
            0u);
  EXPECT_NE(fault_text(regs::ErrorCode::kScanFailed, regs::ErrorDetail::kDeviceGone)
                .find("scanner unplugged"),
            std::string::npos);
}

TEST(PageText, ShiftStartsAtTheLatestStartNotAfterNow) {
  const std::vector<int> starts{6 * 60, 14 * 60, 22 * 60};
  EXPECT_EQ(shift_start(local(2026, 3, 10, 15, 30), starts), local(2026, 3, 10, 14, 0));
  EXPECT_EQ(shift_start(local(2026, 3, 10, 14, 0), starts), local(2026, 3, 10, 14, 0));
  EXPECT_EQ(shift_start(local(2026, 3, 10, 5, 0), starts), local(2026, 3, 9, 22, 0));
  EXPECT_EQ(shift_start(local(2026, 3, 1, 0, 10), starts), local(2026, 2, 28, 22, 0));
  EXPECT_EQ(shift_start(local(2026, 3, 10, 5, 0), {}), 0);
  EXPECT_EQ(parse_created_utc("2026-12-06T22:10:00Z"), 1796595000);
  EXPECT_EQ(parse_created_utc("yesterday"), 0);
}

TEST(PageText, SnapshotCarriesStateLastResultRecentAndShift) {
  std::deque<PageResult> recent;
  PageResult failed{7, report(7, regs::ResultCode::kScanFailed), 0};
  failed.report.mutable_verdict()->add_reasons("scan failed: device gone \"USB\"");
  recent.push_back(failed);
  recent.push_back({6, report(6, regs::ResultCode::kOk), 0});
  PageView view;
  view.station = "press 4";
  view.status.state = regs::State::kFault;
  view.status.error_code = regs::ErrorCode::kScanFailed;
  view.status.error_detail = regs::ErrorDetail::kDeviceGone;
  view.recent = &recent;
  for (const auto& r : recent) view.shift.count(r.report, 1);
  const std::string json = page_snapshot_json(view);
  EXPECT_NE(json.find("\"state\":\"fault\""), std::string::npos) << json;
  // The fault in words, with the failed job's own reason (escaped).
  EXPECT_NE(json.find("(scan failed: device gone \\\"USB\\\")"), std::string::npos) << json;
  EXPECT_NE(json.find("\"last\":{\"record\":7,\"seq\":7"), std::string::npos);
  EXPECT_EQ(json.find("\"picture\""), std::string::npos);  // a failed scan has no map
  EXPECT_NE(json.find("\"recent\":[{\"record\":7"), std::string::npos);
  EXPECT_NE(json.find("{\"record\":6,\"seq\":6"), std::string::npos);
  EXPECT_NE(json.find("\"parts\":2,\"pass\":1,\"fail\":0,\"undecided\":0,\"no_result\":1,"
                      "\"yield_pct\":100"),
            std::string::npos)
      << json;
  EXPECT_NE(json.find("\"report\":\"reports/r000000000006/report.html\""), std::string::npos);
}

// An undecided part is counted apart and lowers the yield (measured, not proven good); its bend
// rows carry the decision and U.
TEST(PageText, UndecidedIsCountedAndItsBendsCarryDecisionAndU) {
  std::deque<PageResult> recent;
  PageResult undecided{9, report(9, regs::ResultCode::kUndecided), 0};
  v1::Bend* bend = undecided.report.add_bends();
  bend->set_springback_uncertainty_deg(0.125);
  bend->set_decision(v1::UNDECIDED);
  recent.push_back(undecided);
  recent.push_back({8, report(8, regs::ResultCode::kOk), 0});
  PageView view;
  view.recent = &recent;
  for (const auto& r : recent) view.shift.count(r.report, 1);
  EXPECT_EQ(view.shift.undecided, 1);
  const std::string json = page_snapshot_json(view);
  EXPECT_NE(json.find("\"verdict\":\"UNDECIDED\""), std::string::npos) << json;
  EXPECT_NE(json.find("\"springback_uncertainty_deg\":0.125,\"decision\":\"UNDECIDED\""),
            std::string::npos)
      << json;
  EXPECT_NE(json.find("\"undecided\":1,\"no_result\":0,\"yield_pct\":50"), std::string::npos)
      << json;
  const v1::InspectionReport copy = page_fields(undecided.report);
  EXPECT_EQ(copy.bends(0).decision(), v1::UNDECIDED);
  EXPECT_EQ(copy.bends(0).springback_uncertainty_deg(), 0.125);
  EXPECT_EQ(copy.verdict().decision(), v1::Verdict::DECISION_UNSPECIFIED);  // as stored
}

TEST(PageText, DeviationPictureIsTheIsometricViewOfReportHtml) {
  const std::string html =
      "<section id='bends'><figure class='view'><svg class='view'>B</svg></figure></section>"
      "<section id='deviation'><div class='views'><figure class='view'><svg class='view'>top"
      "</svg></figure><figure class='view'><svg class='view' viewBox='0 0 5 5'>iso</svg>"
      "<figcaption>isometric view</figcaption></figure></div></section>";
  EXPECT_EQ(deviation_svg_from_report_html(html),
            "<svg xmlns='http://www.w3.org/2000/svg' class='view' viewBox='0 0 5 5'>iso</svg>");
  EXPECT_EQ(deviation_svg_from_report_html("<section id='deviation'><p>missing</p></section>"), "");
  EXPECT_EQ(deviation_svg_from_report_html(""), "");
}

}  // namespace
}  // namespace springscan::daemon
