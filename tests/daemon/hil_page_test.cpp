// Hardware in the loop, the operator page (docs/operator-page.md): the real springscand with
// its http { } section, headless Chromium on the page (cdp_browser.hpp reads its live DOM),
// the simulated PLC driving 20 cycles, PASS and FAIL in turn. The page must show each verdict
// within 1 s of the report reaching the store, and the results table must end with what the
// station published. In the second half, 50 more pages and one page that never reads are
// open: the cycle time must not grow and none of those pages may miss a result.
#include <sys/socket.h>
#include <sys/stat.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <mutex>
#include <sstream>
#include <thread>

#include "cdp_browser.hpp"
#include "daemon/page_text.hpp"
#include "hil_rig.hpp"
#include "page_client.hpp"
#include "tests/analysis/under_sanitizer.hpp"
#include "tests/support/test_paths.hpp"

namespace springscan::daemon {
namespace {

using testing::HilTest;

// Even, so that every other part failing gives a yield of 50 %. Under a sanitizer 8 cycles (4
// without the crowd, 4 with it) look for the same races and leaks at 2.5x less CI time.
constexpr int kCycles = analysis::testing::kUnderSanitizer ? 8 : 20;
constexpr int kExtraPages = 50;

// Records every change of the verdict panel, as the DOM holds it, with the browser's clock
// (Date.now(): the same system clock as the file times the test reads).
constexpr const char* kWatchVerdicts = R"JS((() => {
  window.__seen = [];
  const v = document.getElementById('verdict');
  const note = () => window.__seen.push([v.dataset.seq || '', v.textContent, Date.now()].join('|'));
  new MutationObserver(note).observe(v, {childList: true, characterData: true, subtree: true,
                                         attributes: true});
  return 'watching';
})())JS";

constexpr const char* kRecentRows = R"JS(Array.from(document.querySelectorAll('#recent tbody tr'))
  .map((tr) => Array.from(tr.cells).map((c) => c.textContent).join('|') + '|' +
               tr.querySelector('a').getAttribute('href')).join('\n'))JS";

constexpr const char* kBendRows = R"JS(Array.from(document.querySelectorAll('#bends tr'))
  .map((tr) => Array.from(tr.cells).map((c) => c.textContent).join('|')).join('\n'))JS";

std::vector<std::string> split(const std::string& text, char separator) {
  std::vector<std::string> parts;
  std::stringstream in(text);
  for (std::string part; std::getline(in, part, separator);) parts.push_back(part);
  return parts;
}

double median(std::vector<double> values) {
  std::sort(values.begin(), values.end());
  return values.empty() ? 0.0 : values[values.size() / 2];
}

/// When a record's report.pb was written (the store renames the record into place right after),
/// in ms since the epoch.
double stored_ms(const std::string& record_dir) {
  struct stat st {};
  if (::stat((record_dir + "/report.pb").c_str(), &st) != 0) return 0.0;
  return static_cast<double>(st.st_mtim.tv_sec) * 1e3 +
         static_cast<double>(st.st_mtim.tv_nsec) / 1e6;
}

std::string fixed2(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.2f", value);
  return text;
}

/// 50 open pages, each reading the event stream on its own thread and keeping the last snapshot.
class PageCrowd {
 public:
  PageCrowd(int port, int count) {
    for (int i = 0; i < count; ++i)
      streams_.push_back(std::make_unique<testing::EventStream>(port, 60.0));
    latest_.resize(static_cast<std::size_t>(count));
    for (int i = 0; i < count; ++i) {
      threads_.emplace_back([this, i] {
        for (;;) {
          std::string data = streams_[static_cast<std::size_t>(i)]->next_data();
          if (data.empty()) return;
          std::lock_guard lock(mutex_);
          latest_[static_cast<std::size_t>(i)] = std::move(data);
        }
      });
    }
  }
  ~PageCrowd() {
    for (auto& s : streams_) s->shutdown();
    for (auto& t : threads_) t.join();
  }
  /// How many pages' last snapshot lists every record 1..last.
  int complete(int last) {
    std::lock_guard lock(mutex_);
    int n = 0;
    for (const std::string& data : latest_) {
      bool all = true;
      for (int r = 1; r <= last && all; ++r)
        all = data.find("{\"record\":" + std::to_string(r) + ",") != std::string::npos;
      n += all ? 1 : 0;
    }
    return n;
  }

 private:
  std::vector<std::unique_ptr<testing::EventStream>> streams_;
  std::vector<std::thread> threads_;
  std::mutex mutex_;
  std::vector<std::string> latest_;
};

class HilPageTest : public HilTest {
 protected:
  HilPageTest() {
    // One shift that began an hour ago: the counts cannot restart during the test.
    const std::time_t hour_ago = std::time(nullptr) - 3600;
    std::tm local{};
    localtime_r(&hour_ago, &local);
    char shift[8];
    std::snprintf(shift, sizeof shift, "%02d:%02d", local.tm_hour, local.tm_min);
    // Part 2: the same hat with a tolerance its springback cannot meet, so verdicts alternate.
    std::ofstream(config_path(), std::ios::app)
        << "parts { part_id: 2 name: \"demo hat, tight\" cad_file: \""
        << springscan::test_paths::source("demo/hat-profile.step")
        << "\"\n  settings { verdict { tolerance_mm: 0.5 angle_tolerance_deg: 0.1 } } }\n"
        << "http { address: \"127.0.0.1\" port: 0 shift_starts: \"" << shift << "\" }\n"
        << "station_name: \"press 4\"\n";
  }
};

TEST_F(HilPageTest, BrowserShowsEveryVerdictWithin1sAndCrowdsDoNotSlowTheCycle) {
  const std::string chromium = testing::find_chromium();
  if (chromium.empty()) GTEST_SKIP() << "chromium is not installed (scripts/install-deps.sh)";
  testing::HilDevice device;
  device.scan_duration_s = 0.1;  // 20 cycles within the suite's budget
  device.step_mm = 2.0;
  device.points_per_profile = 120;
  emulate(testing::kGoodSpringback, device);
  auto daemon = start_daemon();
  const int http_port = std::atoi(daemon->early_value("HTTP_PORT").c_str());
  ASSERT_GT(http_port, 0) << "no HTTP_PORT= from springscand";
  auto client = plc(daemon->port());
  wait_online(*client);

  testing::CdpBrowser browser(chromium, "http://127.0.0.1:" + std::to_string(http_port) + "/",
                              dir_.str() + "/chromium-profile");
  ASSERT_TRUE(browser.attach(std::chrono::seconds(60)));
  std::optional<std::string> live;
  for (int i = 0; i < 300 && live != "complete|live"; ++i) {
    live =
        browser.evaluate("document.readyState + '|' + document.getElementById('conn').textContent");
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  ASSERT_EQ(live, "complete|live");
  ASSERT_EQ(browser.evaluate(kWatchVerdicts), "watching");

  std::vector<double> cycle_ms[2];  // without, with the crowd
  std::unique_ptr<PageCrowd> crowd;
  int stalled = -1;
  for (int k = 1; k <= kCycles; ++k) {
    if (k == kCycles / 2 + 1) {
      crowd = std::make_unique<PageCrowd>(http_port, kExtraPages);
      stalled = testing::connect_loopback(http_port, 2048);
      ASSERT_TRUE(testing::send_all(stalled, "GET /events HTTP/1.1\r\n\r\n"));
    }
    const std::uint16_t part = k % 2 == 1 ? 1 : 2;
    auto cycle = client->run_cycle(static_cast<std::uint16_t>(500 + k), part);
    ASSERT_TRUE(cycle.ok()) << cycle.message();
    ASSERT_EQ(cycle->result.seq, k);
    EXPECT_EQ(cycle->part_ok, part == 1);
    cycle_ms[crowd ? 1 : 0].push_back(cycle->trigger_to_valid_ms);
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(1500));  // the last one's second

  // Every verdict the station published, in the DOM within 1 s of its report being stored.
  const auto seen = browser.evaluate("window.__seen.join('\\n')");
  ASSERT_TRUE(seen.has_value());
  double worst_ms = 0.0;
  for (int k = 1; k <= kCycles; ++k) {
    const v1::InspectionReport published = report(k);
    const std::string verdict = page_verdict(published);
    EXPECT_EQ(verdict, k % 2 == 1 ? "PASS" : "FAIL");
    const double stored = stored_ms(
        reports() + "/r" + std::string(12 - std::to_string(k).size(), '0') + std::to_string(k));
    double shown = -1.0;
    for (const std::string& line : split(*seen, '\n')) {
      const auto f = split(line, '|');
      if (f.size() == 3 && f[0] == std::to_string(k) && f[1] == verdict) {
        shown = std::stod(f[2]);
        break;
      }
    }
    ASSERT_GE(shown, 0.0) << "result " << k << " (" << verdict << ") never shown:\n" << *seen;
    EXPECT_LT(shown - stored, 1000.0) << "result " << k;
    worst_ms = std::max(worst_ms, shown - stored);
  }
  // The table ends with what the station published, newest first, each row linked to its
  // report; the bend table is the last report's.
  const auto rows = split(browser.evaluate(kRecentRows).value_or(""), '\n');
  ASSERT_EQ(rows.size(), static_cast<std::size_t>(kCycles));
  for (int k = 1; k <= kCycles; ++k) {
    const v1::InspectionReport r = report(k);
    const auto cells = split(rows[static_cast<std::size_t>(kCycles - k)], '|');
    ASSERT_EQ(cells.size(), 7u);  // six cells, then the link's target
    EXPECT_EQ(cells[0], std::to_string(r.result_seq()));
    EXPECT_EQ(cells[2], std::to_string(r.job_id()));
    EXPECT_EQ(cells[3], r.input().part_id());
    EXPECT_EQ(cells[4], page_verdict(r));
    EXPECT_EQ(cells[6], record_url(static_cast<std::uint64_t>(k), "report.html"));
  }
  const v1::InspectionReport last = report(kCycles);
  const auto bends = split(browser.evaluate(kBendRows).value_or(""), '\n');
  ASSERT_EQ(bends.size(), static_cast<std::size_t>(last.bends_size()));
  for (int j = 0; j < last.bends_size(); ++j) {
    const auto cells = split(bends[static_cast<std::size_t>(j)], '|');
    const v1::Bend& b = last.bends(j);
    ASSERT_EQ(cells.size(), 7u);
    EXPECT_EQ(cells[0], "B" + std::to_string(b.id()));
    EXPECT_EQ(cells[1], fixed2(b.nominal_angle_deg()));
    EXPECT_EQ(cells[2], fixed2(b.measured_angle_deg()));
    EXPECT_EQ(cells[3], fixed2(b.springback_deg()));
    char u[32];
    std::snprintf(u, sizeof u, "%.3f", b.springback_uncertainty_deg());
    EXPECT_EQ(cells[4], u);
    EXPECT_EQ(cells[5], fixed2(b.angle_tolerance_deg()));
    EXPECT_EQ(cells[6], b.decision() == v1::UNDECIDED ? "UNDECIDED" : b.pass() ? "OK" : "OUT");
  }
  EXPECT_EQ(browser.evaluate("document.getElementById('verdict').textContent"), "FAIL");
  EXPECT_EQ(browser.evaluate("String(document.getElementById('map').naturalWidth > 0)"), "true");
  EXPECT_EQ(browser.evaluate("document.getElementById('count-parts').textContent + '|' + "
                             "document.getElementById('yield').textContent"),
            std::to_string(kCycles) + "|50.0 %");
  // No page of the crowd missed a result; the crowd did not slow the cycle.
  for (int i = 0; i < 50 && crowd->complete(kCycles) < kExtraPages; ++i)
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  EXPECT_EQ(crowd->complete(kCycles), kExtraPages);
  const double alone = median(cycle_ms[0]), crowded = median(cycle_ms[1]);
  // Generous against a busy 2-core machine; the figures printed below are what it measured.
  EXPECT_LT(crowded, alone * 1.5 + 200.0) << "median cycle " << alone << " ms alone";
  std::printf(
      "[ page    ] slowest page update %.0f ms after the report was stored; median cycle "
      "%.0f ms with the browser, %.0f ms with %d more pages and a stalled one\n",
      worst_ms, alone, crowded, kExtraPages);
  crowd.reset();
  ::close(stalled);
  // The page's server stops with the daemon, cleanly and quickly (civetweb's stop is woken).
  const auto stopping = std::chrono::steady_clock::now();
  EXPECT_EQ(daemon->stop(SIGTERM), 0);
  EXPECT_LT(std::chrono::steady_clock::now() - stopping, std::chrono::seconds(3));
}

}  // namespace
}  // namespace springscan::daemon
