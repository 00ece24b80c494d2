// The result publisher against Debian's mosquitto and a python3-paho-mqtt subscriber
// (mqtt_rig.hpp), without the station: a report store holding a backlog while the broker is
// down is published, in order and once, when the broker comes back; the figure (backlog
// drained) goes to docs/performance.md.
#include "daemon/result_publisher.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <cstdio>
#include <fstream>
#include <thread>

#include "daemon/register_map.hpp"
#include "mqtt_rig.hpp"
#include "test_rig.hpp"
#include "tests/support/test_paths.hpp"

namespace springscan::daemon {
namespace {

using testing::PahoSubscriber;

v1::InspectionReport small_report(int k) {
  v1::InspectionReport r;
  r.set_schema("springscan.report.v1");
  r.set_result_seq(regs::result_seq_from_record(static_cast<std::uint64_t>(k)));
  r.set_job_id(k);
  r.mutable_input()->set_part_id("1");
  for (int b = 0; b < 4; ++b) {
    v1::Bend* bend = r.add_bends();
    bend->set_id(b);
    bend->set_measured(true);
    bend->set_springback_deg(0.1 * b + 0.001 * k);
  }
  return r;
}

TEST(ResultPublisherTest, BacklogWhileTheBrokerIsDownIsPublishedInOrderWhenItComesBack) {
  const MosquittoLibrary library;
  testing::TempDir dir("springscan-publisher");
  Log log = Log::to_stderr(LogLevel::kError);
  auto store = ReportStore::open({dir.str() + "/reports", 1000});
  ASSERT_TRUE(store.ok()) << store.message();
  std::filesystem::create_directories(dir.str() + "/broker");
  testing::MosquittoBroker broker(dir.str() + "/broker", /*persistent=*/true);
  PahoSubscriber subscriber(springscan::test_paths::source("tests/daemon/mqtt_subscriber.py"),
                            dir.str(), broker.port(), "springscan/v1");
  ASSERT_TRUE(subscriber.wait_for(
      [](const auto& m) { return PahoSubscriber::count_events(m, "subscribed") >= 1; }, 30.0));
  broker.stop();

  constexpr int kBacklog = 100;
  for (int k = 1; k <= kBacklog; ++k) {
    ASSERT_TRUE(store->persist(static_cast<std::uint64_t>(k), report_only(small_report(k))).ok());
  }
  MqttSettings settings;
  settings.port = broker.port();
  settings.station = "cell-9";
  settings.retry_initial_s = 0.1;
  settings.retry_max_s = 0.2;
  auto publisher = ResultPublisher::start(settings, *store, 4242, log);
  ASSERT_TRUE(publisher.ok()) << publisher.message();
  std::this_thread::sleep_for(std::chrono::milliseconds(500));  // refused, retrying
  EXPECT_EQ((*publisher)->acked_record(), 0u);

  const auto start = std::chrono::steady_clock::now();
  broker.start();
  const std::string json_topic = "springscan/v1/cell-9/result/json";
  ASSERT_TRUE(subscriber.wait_for(
      [&](const auto& m) { return PahoSubscriber::on(m, json_topic).size() >= kBacklog; }, 60.0));
  const double drained_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::printf("[figure] mqtt backlog of %d results drained %.2f s after the broker restart\n",
              kBacklog, drained_s);
  RecordProperty("backlog_drain_s", std::to_string(drained_s));
  // Every record once, in order, on both topics; the acknowledged record reaches the file.
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  const auto all = subscriber.messages();
  for (const std::string topic : {"springscan/v1/cell-9/result", json_topic.c_str()}) {
    const auto got = PahoSubscriber::on(all, topic);
    ASSERT_EQ(got.size(), static_cast<std::size_t>(kBacklog)) << topic;
    for (int k = 0; k < kBacklog; ++k) {
      EXPECT_EQ(testing::prop(got[static_cast<std::size_t>(k)], "record"), std::to_string(k + 1));
      EXPECT_EQ(testing::prop(got[static_cast<std::size_t>(k)], "boot_id"), "4242");
    }
  }
  EXPECT_EQ((*publisher)->acked_record(), static_cast<std::uint64_t>(kBacklog));
  publisher->reset();
  std::ifstream acked(dir.str() + "/reports/mqtt_acked_record");
  int last = 0;
  acked >> last;
  EXPECT_EQ(last, kBacklog);
}

}  // namespace
}  // namespace springscan::daemon
