// The operator page's server over a real report store (daemon/page_server.hpp): what it serves,
// what it refuses, and that a page that stops reading costs the station nothing.
#include "daemon/page_server.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <thread>

#include "analysis/io/file_io.hpp"
#include "page_client.hpp"
#include "test_rig.hpp"

namespace springscan::daemon {
namespace {

namespace fs = std::filesystem;
using testing::EventStream;
using testing::http_get;
using testing::raw_request;

constexpr const char* kSecret = "SECRET-OUTSIDE-THE-STORE";

/// A result as the runner stores it: verdict, bends, deviation and a small coloured cloud.
analysis::InspectionOutcome outcome(std::uint32_t seq, bool pass, std::size_t note_chars = 0) {
  v1::InspectionReport r;
  r.set_result_seq(seq);
  r.set_job_id(100 + seq);
  r.set_result_code(pass ? 0 : 1);
  r.set_created_utc("2026-12-06T10:00:00Z");
  r.mutable_input()->set_part_id("1");
  r.mutable_verdict()->set_pass(pass);
  if (!pass) r.mutable_verdict()->add_reasons("bend 2: springback 1.80 deg exceeds 1.00 deg");
  if (note_chars > 0) r.mutable_verdict()->add_reasons(std::string(note_chars, 'n'));
  r.mutable_deviation()->set_points(400);
  r.mutable_deviation()->set_rms(0.05);
  r.mutable_deviation()->set_tolerance_mm(0.5);
  for (int b = 0; b < 2; ++b) {
    v1::Bend* bend = r.add_bends();
    bend->set_id(b + 1);
    bend->set_measured(true);
    bend->set_nominal_angle_deg(90.0);
    bend->set_measured_angle_deg(pass || b == 0 ? 89.5 : 88.2);
    bend->set_springback_deg(pass || b == 0 ? 0.5 : 1.8);
    bend->set_angle_tolerance_deg(1.0);
    bend->set_pass(pass || b == 0);
  }
  analysis::InspectionOutcome out = report_only(r);
  for (int i = 0; i < 400; ++i) {
    out.deviation_cloud.points.emplace_back(i % 20, i / 20, 0.01 * (i % 7));
    out.deviation_cloud.scalars.push_back(0.01 * (i % 7));
  }
  return out;
}

class PageServerTest : public ::testing::Test {
 protected:
  PageServerTest() : dir_("springscan-page") {
    fs::create_directories(dir_.str() + "/reports");
    std::ofstream(dir_.str() + "/secret.txt") << kSecret;
    auto store = ReportStore::open({dir_.str() + "/reports", 1000});
    if (!store) throw std::runtime_error(store.message());
    store_.emplace(std::move(*store));
  }
  void persist(std::uint64_t record, bool pass, std::size_t note_chars = 0) {
    ASSERT_TRUE(
        store_->persist(record, outcome(static_cast<std::uint32_t>(record), pass, note_chars))
            .ok());
  }
  void start(PageSettings settings = {}) {
    settings.enabled = true;
    settings.port = 0;
    auto server = PageServer::start(settings, *store_, "press 4", log_);
    ASSERT_TRUE(server.ok()) << server.message();
    server_ = std::move(*server);
  }

  testing::TempDir dir_;
  Log log_ = Log::to_stderr(LogLevel::kWarning);
  std::optional<ReportStore> store_;
  std::unique_ptr<PageServer> server_;
};

TEST(PageRecordPath, AcceptsOnlyTheStoresOwnNames) {
  bool picture = false;
  EXPECT_EQ(page_record_path("/reports/r000000000042/report.html", picture), 42u);
  EXPECT_FALSE(picture);
  EXPECT_EQ(page_record_path("/reports/r000000000042/deviation.svg", picture), 42u);
  EXPECT_TRUE(picture);
  for (const char* bad :
       {"/reports/r000000000042/report.pb", "/reports/r00000000042/report.html",
        "/reports/r0000000000420/report.html", "/reports/r00000000004a/report.html",
        "/reports/r000000000042/../report.html", "/reports/../r000000000042/report.html",
        "/reports/r000000000042/report.html/", "/reports/r000000000042//report.html", ""}) {
    EXPECT_EQ(page_record_path(bad, picture), 0u) << bad;
  }
}

TEST_F(PageServerTest, ServesThePageTheSnapshotAndTheStoresReports) {
  persist(1, true);
  persist(2, false);
  start();
  const auto page = http_get(server_->port(), "/");
  ASSERT_EQ(page.status, 200) << page.head;
  EXPECT_NE(page.head.find("text/html"), std::string::npos);
  EXPECT_NE(page.head.find("Content-Security-Policy: default-src 'none'"), std::string::npos);
  EXPECT_NE(page.body.find("new EventSource('events')"), std::string::npos);
  // Self-contained: no resource from anywhere else.
  EXPECT_EQ(page.body.find("http://"), std::string::npos);
  EXPECT_EQ(page.body.find("https://"), std::string::npos);

  const auto state = http_get(server_->port(), "/state.json");
  ASSERT_EQ(state.status, 200);
  EXPECT_NE(state.body.find("\"last\":{\"record\":2,\"seq\":2,\"job_id\":102"), std::string::npos)
      << state.body;
  EXPECT_NE(state.body.find("\"verdict\":\"FAIL\""), std::string::npos);
  EXPECT_NE(state.body.find("bend 2: springback 1.80 deg exceeds 1.00 deg"), std::string::npos);

  const auto report = http_get(server_->port(), "/reports/r000000000001/report.html");
  ASSERT_EQ(report.status, 200);
  EXPECT_EQ(report.body, *analysis::read_file_bytes(store_->record_path(1) + "/report.html"));
  const auto map = http_get(server_->port(), "/reports/r000000000002/deviation.svg");
  ASSERT_EQ(map.status, 200);
  EXPECT_NE(map.head.find("image/svg+xml"), std::string::npos);
  EXPECT_EQ(map.body.rfind("<svg xmlns='http://www.w3.org/2000/svg'", 0), 0u);
  EXPECT_NE(map.body.find("data:image/png;base64,"), std::string::npos);
  EXPECT_EQ(http_get(server_->port(), "/reports/r000000000003/report.html").status, 404);
}

TEST_F(PageServerTest, BadRequestsGet4xxAndNothingOutsideTheStore) {
  persist(1, true);
  start();
  const int port = server_->port();
  for (const char* target :
       {"/secret.txt", "/../secret.txt", "/reports/../../secret.txt", "/%2e%2e/secret.txt",
        "/reports/r000000000001/../../../secret.txt", "/reports/r000000000001/..%2f..%2fsecret.txt",
        "/reports/%2e%2e/%2e%2e/secret.txt", "/..%5c..%5csecret.txt", "//etc/passwd",
        "/reports/r000000000001/report.pb", "/reports/r000000000001/", "/reports/",
        "/../../../../../../etc/passwd", "/index.html/../../secret.txt", "/unknown"}) {
    const auto answer = http_get(port, target);
    EXPECT_GE(answer.status, 400) << target;
    EXPECT_LT(answer.status, 500) << target;
    EXPECT_EQ(answer.body.find(kSecret), std::string::npos) << target;
    EXPECT_EQ(answer.body.find("root:"), std::string::npos) << target;
  }
  // Read-only: no other method.
  for (const char* method : {"POST", "PUT", "DELETE", "PATCH"}) {
    const auto answer =
        raw_request(port, std::string(method) + " / HTTP/1.1\r\nContent-Length: 0\r\n\r\n");
    EXPECT_EQ(answer.status, 405) << method;
  }
  // Huge headers: one of 100 KB, and 2000 small ones (16 KB in all).
  const auto huge =
      raw_request(port, "GET / HTTP/1.1\r\nX-Big: " + std::string(100000, 'a') + "\r\n\r\n");
  EXPECT_GE(huge.status, 400);
  EXPECT_LT(huge.status, 500);
  std::string many = "GET / HTTP/1.1\r\n";
  for (int i = 0; i < 2000; ++i) many += "X-H" + std::to_string(i) + ": v\r\n";
  const auto many_answer = raw_request(port, many + "\r\n");
  EXPECT_GE(many_answer.status, 400);
  EXPECT_LT(many_answer.status, 500);
  const auto garbage = raw_request(port, "\x01\x02 garbage\r\n\r\n");
  EXPECT_TRUE(garbage.status == 0 || (garbage.status >= 400 && garbage.status < 500));
  // Still serving after all of it.
  EXPECT_EQ(http_get(port, "/").status, 200);
}

TEST_F(PageServerTest, EventStreamPushesEveryChangeAndNewRecords) {
  persist(1, true);
  start();
  EventStream stream(server_->port());
  ASSERT_TRUE(stream.ok());
  const std::string first = stream.next_data();
  EXPECT_NE(first.find("\"schema\":\"springscan.page.v1\""), std::string::npos) << first;
  MachineStatus status;
  status.state = regs::State::kAcquiring;
  status.scanner_online = true;
  const auto sent = std::chrono::steady_clock::now();
  server_->feed().on_status(status);
  std::string scanning;
  while (scanning.find("\"state\":\"scanning\"") == std::string::npos &&
         !(scanning = stream.next_data()).empty()) {
  }
  EXPECT_NE(scanning.find("\"state\":\"scanning\""), std::string::npos) << scanning;
  EXPECT_LT(std::chrono::steady_clock::now() - sent, std::chrono::seconds(1));
  persist(2, false);  // the feed finds it in the store, as the MQTT publisher does
  std::string result;
  while (result.find("\"last\":{\"record\":2") == std::string::npos &&
         !(result = stream.next_data()).empty()) {
  }
  EXPECT_NE(result.find("\"last\":{\"record\":2"), std::string::npos) << result;
  EXPECT_NE(result.find("\"shift\":{"), std::string::npos);
}

// CALIBRATION_DRIFT (the check part's latch) reaches the page as a flag of the status, and
// leaves it when a check part passes again.
TEST_F(PageServerTest, CalibrationDriftIsShownWhileLatched) {
  start();
  EventStream stream(server_->port());
  ASSERT_TRUE(stream.ok());
  EXPECT_NE(stream.next_data().find("\"calibration_drift\":false"), std::string::npos);
  MachineStatus status;
  status.scanner_online = true;
  for (const bool drift : {true, false}) {
    server_->feed().on_status(status, drift);
    const std::string wanted = std::string("\"calibration_drift\":") + (drift ? "true" : "false");
    std::string seen;
    while (seen.find(wanted) == std::string::npos && !(seen = stream.next_data()).empty()) {
    }
    EXPECT_NE(seen.find(wanted), std::string::npos) << seen;
    status.ready = !status.ready;  // a second change, so that the stream has news each time
  }
}

TEST_F(PageServerTest, APageThatNeverReadsIsDroppedAndBlocksNobody) {
  // The last result's reasons go into every snapshot: a long one makes each ~100 KB, so the
  // stalled page's socket buffers fill after a few dozen changes.
  persist(1, true);
  persist(2, false, 100000);
  PageSettings settings;
  settings.write_timeout_ms = 1000;
  start(settings);
  const int stalled = testing::connect_loopback(server_->port(), 2048);
  ASSERT_GE(stalled, 0);
  ASSERT_TRUE(testing::send_all(stalled, "GET /events HTTP/1.1\r\n\r\n"));
  // A page that reads all along, on its own thread, keeping the newest snapshot.
  EventStream reader(server_->port());
  std::mutex mutex;
  std::string latest;
  std::thread reading([&] {
    for (std::string data; !(data = reader.next_data()).empty();) {
      std::lock_guard lock(mutex);
      latest = std::move(data);
    }
  });
  // The event loop's side: on_status never waits, however full the stalled page's socket is.
  // Had it waited for the stalled page's write, it would have taken the write timeout (1 s);
  // the bound leaves room for a busy machine's scheduling.
  MachineStatus status;
  std::chrono::steady_clock::duration slowest{};
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(20);
  int changes = 0;
  while (server_->stats().dropped.load() == 0 && std::chrono::steady_clock::now() < deadline) {
    status.state = changes++ % 2 == 0 ? regs::State::kAcquiring : regs::State::kAnalyzing;
    const auto before = std::chrono::steady_clock::now();
    server_->feed().on_status(status);
    slowest = std::max(slowest, std::chrono::steady_clock::now() - before);
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  EXPECT_EQ(server_->stats().dropped.load(), 1u) << changes << " changes";
  EXPECT_LT(slowest, std::chrono::milliseconds(250));
  // The reading page is still served, with the newest state.
  status.state = regs::State::kFault;
  server_->feed().on_status(status);
  const auto fault_deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  bool fault_seen = false;
  while (!fault_seen && std::chrono::steady_clock::now() < fault_deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    std::lock_guard lock(mutex);
    fault_seen = latest.find("\"state\":\"fault\"") != std::string::npos &&
                 latest.find("\"last\":{\"record\":2") != std::string::npos;
  }
  EXPECT_TRUE(fault_seen);
  reader.shutdown();
  reading.join();
  ::close(stalled);
}

TEST_F(PageServerTest, RefusesPagesBeyondMaxClients) {
  PageSettings settings;
  settings.max_clients = 2;
  start(settings);
  EventStream a(server_->port()), b(server_->port());
  ASSERT_FALSE(a.next_data().empty());
  ASSERT_FALSE(b.next_data().empty());
  EXPECT_EQ(http_get(server_->port(), "/events").status, 503);
  EXPECT_EQ(http_get(server_->port(), "/").status, 200);  // the quick threads stay free
}

}  // namespace
}  // namespace springscan::daemon
