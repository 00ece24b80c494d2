// The report in a real browser: headless Chromium renders the page to a screenshot
// that must not be blank, and its DOM must hold the bend rows. Skips only where Chromium is
// not installed. The browser runs in its own process group, killed after a timeout.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <thread>

#include "report/report_html.hpp"
#include "report/trend_html.hpp"
#include "tests/report/png_decode.hpp"
#include "tests/report/report_fixture.hpp"

namespace springscan::report {
namespace {

namespace fs = std::filesystem;

std::string find_chromium() {
  const char* path = std::getenv("PATH");
  std::stringstream dirs(path ? path : "/usr/bin:/bin");
  for (std::string dir; std::getline(dirs, dir, ':');)
    for (const char* name : {"chromium", "chromium-browser"})
      if (!dir.empty() && access((fs::path(dir) / name).c_str(), X_OK) == 0)
        return (fs::path(dir) / name).string();
  return "";
}

std::string read_file(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

// Runs argv with stdout into `stdout_path` and stderr discarded; returns the exit status, or
// -1 when it had to be killed after `timeout`. The whole process group (Chromium's helpers
// included) is killed at the end, so no browser outlives the test.
int run_bounded(const std::vector<std::string>& argv, const fs::path& stdout_path,
                std::chrono::seconds timeout) {
  std::vector<char*> args;
  for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  const pid_t pid = fork();
  if (pid == 0) {
    setpgid(0, 0);
    const int out = open(stdout_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    const int null = open("/dev/null", O_WRONLY);
    if (out >= 0) dup2(out, STDOUT_FILENO);
    if (null >= 0) dup2(null, STDERR_FILENO);
    execv(args[0], args.data());
    _exit(127);
  }
  if (pid < 0) return -2;
  setpgid(pid, pid);  // also from here, so the group exists before we might kill it
  int status = 0;
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  bool exited = false;
  while (std::chrono::steady_clock::now() < deadline) {
    if (waitpid(pid, &status, WNOHANG) == pid) {
      exited = true;
      break;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  kill(-pid, SIGKILL);
  if (!exited) {
    waitpid(pid, &status, 0);
    return -1;
  }
  return WIFEXITED(status) ? WEXITSTATUS(status) : -3;
}

class Browser : public ::testing::Test {
 protected:
  void SetUp() override {
    chromium_ = find_chromium();
    if (chromium_.empty())
      GTEST_SKIP() << "chromium is not installed (Debian package chromium; "
                      "scripts/install-deps.sh installs it)";
    dir_ = fs::temp_directory_path() / ("springscan_browser_test_" + std::to_string(getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    const auto fixture = testing::make_fixture(20'000);
    auto written = write_report_html_in_dir(dir_, fixture.report, fixture.cloud);
    ASSERT_TRUE(written.ok()) << written.message();
    page_ = *written;
  }
  void TearDown() override {
    if (!dir_.empty()) fs::remove_all(dir_);
  }
  std::vector<std::string> browser_args(const std::string& profile) const {
    return {chromium_,
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--disable-quic",
            "--no-first-run",
            "--disable-background-networking",
            "--disable-component-update",
            "--disable-sync",
            "--user-data-dir=" + (dir_ / profile).string(),
            "--window-size=1200,1600"};
  }
  std::string chromium_;
  fs::path dir_, page_;
};

TEST_F(Browser, ScreenshotShowsTheRenderedReport) {
  const fs::path shot = dir_ / "shot.png";
  auto args = browser_args("profile-shot");
  args.push_back("--screenshot=" + shot.string());
  args.push_back("file://" + page_.string());
  const int status = run_bounded(args, dir_ / "shot.log", std::chrono::seconds(90));
  ASSERT_EQ(status, 0) << "chromium --screenshot failed or timed out (-1)";
  std::string why;
  auto png = testing::decode_png(read_file(shot), &why);
  ASSERT_TRUE(png) << why;
  EXPECT_EQ(png->width, 1200);
  std::set<std::uint32_t> colours;
  std::size_t non_white = 0;
  const auto n = static_cast<std::size_t>(png->width) * static_cast<std::size_t>(png->height);
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint8_t* p = png->pixels.data() + i * static_cast<std::size_t>(png->channels);
    colours.insert((std::uint32_t{p[0]} << 16) | (std::uint32_t{p[1]} << 8) | p[2]);
    non_white += (p[0] < 245 || p[1] < 245 || p[2] < 245) ? 1 : 0;
  }
  // The red FAIL banner and the colour maps: many colours, a good share of ink.
  EXPECT_GT(colours.size(), 500u);
  EXPECT_GT(non_white, n / 10);
  const std::uint8_t* banner =
      png->pixels.data() +
      (static_cast<std::size_t>(120) * static_cast<std::size_t>(png->width) + 600) *
          static_cast<std::size_t>(png->channels);
  EXPECT_GT(banner[0], 150);  // the FAIL banner is red
  EXPECT_LT(banner[1], 90);
}

TEST_F(Browser, DomHoldsTheBendRowsAndVerdict) {
  auto args = browser_args("profile-dom");
  args.push_back("--dump-dom");
  args.push_back("file://" + page_.string());
  const int status = run_bounded(args, dir_ / "dom.html", std::chrono::seconds(90));
  ASSERT_EQ(status, 0) << "chromium --dump-dom failed or timed out (-1)";
  const std::string dom = read_file(dir_ / "dom.html");
  ASSERT_FALSE(dom.empty());
  // The browser serialises attributes with double quotes, whatever the source used.
  for (int id = 1; id <= 4; ++id)
    EXPECT_NE(dom.find("id=\"bend-" + std::to_string(id) + "\""), std::string::npos) << id;
  EXPECT_NE(dom.find("class=\"banner fail\""), std::string::npos);
  EXPECT_NE(dom.find("HAT-7 &lt;rev&amp;B&gt;"), std::string::npos);
  EXPECT_NE(dom.find("NOT MEASURED"), std::string::npos);
}

// The trend page (report/trend_html.hpp) in the same browser: a non-blank screenshot with the
// red of the flagged points, and the table and charts in the DOM.
class TrendBrowser : public Browser {
 protected:
  void SetUp() override {
    chromium_ = find_chromium();
    if (chromium_.empty())
      GTEST_SKIP() << "chromium is not installed (Debian package chromium; "
                      "scripts/install-deps.sh installs it)";
    dir_ = fs::temp_directory_path() / ("springscan_trend_browser_" + std::to_string(getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    std::vector<v1::InspectionReport> reports;
    for (int k = 0; k < 60; ++k) {
      v1::InspectionReport r;
      r.mutable_input()->set_part_id("HAT-7");
      r.set_result_seq(static_cast<std::uint32_t>(k + 1));
      v1::Bend* b = r.add_bends();
      b->set_id(1);
      b->set_measured(true);
      b->set_angle_tolerance_deg(1.0);
      b->set_springback_deg(0.3 + 0.05 * std::sin(k * 1.7) + (k == 40 ? 0.6 : 0.0));
      reports.push_back(r);
    }
    TrendPageInfo info;
    info.reports = reports.size();
    page_ = dir_ / "trend.html";
    std::ofstream(page_) << render_trend_html(collect_characteristics(reports), info);
  }
};

TEST_F(TrendBrowser, ScreenshotShowsTheCharts) {
  const fs::path shot = dir_ / "shot.png";
  auto args = browser_args("profile-trend");
  args.push_back("--screenshot=" + shot.string());
  args.push_back("file://" + page_.string());
  ASSERT_EQ(run_bounded(args, dir_ / "shot.log", std::chrono::seconds(90)), 0)
      << "chromium --screenshot failed or timed out (-1)";
  std::string why;
  auto png = testing::decode_png(read_file(shot), &why);
  ASSERT_TRUE(png) << why;
  std::size_t ink = 0, red = 0;
  const auto n = static_cast<std::size_t>(png->width) * static_cast<std::size_t>(png->height);
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint8_t* p = png->pixels.data() + i * static_cast<std::size_t>(png->channels);
    ink += (p[0] < 200 || p[1] < 200 || p[2] < 200) ? 1 : 0;
    red += (p[0] > 180 && p[1] < 90 && p[2] < 90) ? 1 : 0;
  }
  EXPECT_GT(ink, n / 200);  // text, axes, lines: not a blank page
  EXPECT_GT(red, 10u);      // the tolerance lines and the flagged point
}

TEST_F(TrendBrowser, DomHoldsTheTableAndCharts) {
  auto args = browser_args("profile-trend-dom");
  args.push_back("--dump-dom");
  args.push_back("file://" + page_.string());
  ASSERT_EQ(run_bounded(args, dir_ / "dom.html", std::chrono::seconds(90)), 0);
  const std::string dom = read_file(dir_ / "dom.html");
  EXPECT_NE(dom.find("id=\"characteristics\""), std::string::npos);
  EXPECT_NE(dom.find("class=\"individuals\""), std::string::npos);
  EXPECT_NE(dom.find("class=\"moving-range\""), std::string::npos);
  EXPECT_NE(dom.find("class=\"flagged\""), std::string::npos);
}

}  // namespace
}  // namespace springscan::report
