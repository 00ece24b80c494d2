// Hardware in the loop, results to the plant (hil_rig.hpp, mqtt_rig.hpp): springscand under the
// emulated scanner and the simulated PLC publishes every result to Debian's mosquitto, and a
// third-party client (python3-paho-mqtt) receives them. The broker is stopped in the middle of
// a run and started again: every result arrives, in order (a broker's QoS 1 redelivery dropped
// as a consumer drops it).
// Figures (publish latency, backlog drained) are printed for docs/performance.md.
#include <sys/stat.h>

#include <chrono>
#include <cstdio>
#include <fstream>
#include <set>

#include "analysis/io/file_io.hpp"
#include "hil_rig.hpp"
#include "mqtt_rig.hpp"
#include "tests/support/test_paths.hpp"

namespace springscan::daemon {
namespace {

using testing::HilTest;
using testing::Message;
using testing::PahoSubscriber;

constexpr const char* kPrefix = "springscan/v1";
constexpr const char* kStation = "press-4";
const std::string kTopic = std::string(kPrefix) + "/" + kStation;
constexpr double kArrivalTimeout_s = 60.0;

class HilMqttTest : public HilTest {
 protected:
  /// Adds the mqtt { } section to the rig's config (retries every second at most).
  void add_mqtt(int port, const std::string& extra = "") const {
    std::ofstream(config_path(), std::ios::app)
        << "station_name: \"" << kStation << "\"\nmqtt { host: \"127.0.0.1\" port: " << port
        << " retry_max_s: 1 " << extra << "}\n";
  }
  std::string subscriber_script() const {
    return springscan::test_paths::source("tests/daemon/mqtt_subscriber.py");
  }
  std::string broker_dir(const std::string& name) const {
    const std::string d = dir_.str() + "/" + name;
    std::filesystem::create_directories(d);
    return d;
  }
  int boot_id() const {
    int id = 0;
    std::ifstream(reports() + "/boot_id") >> id;
    return id;
  }
  /// When record `record` was renamed into the store (its directory's mtime), unix seconds.
  double persisted_at(int record) const {
    char name[32];
    std::snprintf(name, sizeof name, "/r%012d", record);
    struct stat st {};
    if (::stat((reports() + name).c_str(), &st) != 0) return 0.0;
    return static_cast<double>(st.st_mtim.tv_sec) + st.st_mtim.tv_nsec * 1e-9;
  }
  /// The result messages on `topic` in arrival order, a redelivery of a message already
  /// received (same boot id and record) dropped: QoS 1 is at least once, and across a broker
  /// restart the broker may deliver a message twice (docs/plant-integration.md, "Delivery").
  /// What the daemon publishes again after its own restart has a new boot id and is kept.
  static std::vector<Message> first_arrivals(const std::vector<Message>& all,
                                             const std::string& topic) {
    std::vector<Message> out;
    std::set<std::string> seen;
    for (const auto& m : PahoSubscriber::on(all, topic))
      if (seen.insert(testing::prop(m, "boot_id") + "/" + testing::prop(m, "record")).second)
        out.push_back(m);
    return out;
  }
  /// The record numbers of first_arrivals, in arrival order.
  static std::vector<int> records(const std::vector<Message>& all, const std::string& topic) {
    std::vector<int> out;
    for (const auto& m : first_arrivals(all, topic))
      out.push_back(std::stoi(testing::prop(m, "record")));
    return out;
  }
  static bool has_records(const std::vector<Message>& all, int n) {
    return records(all, kTopic + "/result/json").size() >= static_cast<std::size_t>(n) &&
           records(all, kTopic + "/result").size() >= static_cast<std::size_t>(n);
  }
  void run_cycles(simulators::PlcClient& client, int first_job, int count) {
    for (int i = 0; i < count; ++i) {
      auto cycle = client.run_cycle(static_cast<std::uint16_t>(first_job + i), 1);
      ASSERT_TRUE(cycle.ok()) << cycle.message();
      ASSERT_TRUE(cycle->accepted);
      EXPECT_EQ(cycle->result.code, regs::ResultCode::kOk);
    }
  }
};

TEST_F(HilMqttTest, EveryResultReachesAPahoSubscriberInOrderThroughABrokerRestart) {
  // The broker keeps its state across the restart as a plant broker does, so the subscriber's
  // persistent session holds what is published before it reconnects.
  testing::MosquittoBroker broker(broker_dir("broker"), /*persistent=*/true);
  PahoSubscriber subscriber(subscriber_script(), dir_.str(), broker.port(), kPrefix);
  ASSERT_TRUE(subscriber.wait_for(
      [](const auto& m) { return PahoSubscriber::count_events(m, "subscribed") >= 1; }, 30.0));
  add_mqtt(broker.port());
  emulate(testing::kGoodSpringback);
  auto daemon = start_daemon();
  auto client = plc(daemon->port());
  wait_online(*client);

  run_cycles(*client, 100, 2);
  ASSERT_TRUE(
      subscriber.wait_for([](const auto& m) { return has_records(m, 2); }, kArrivalTimeout_s));
  const auto before_outage = subscriber.messages();

  // The broker goes away; the PLC handshake and the analysis go on as before.
  broker.stop();
  run_cycles(*client, 102, 2);
  EXPECT_EQ(record_count(), 4);
  const auto restart = std::chrono::system_clock::now();
  broker.start();
  ASSERT_TRUE(
      subscriber.wait_for([](const auto& m) { return has_records(m, 4); }, kArrivalTimeout_s))
      << broker.log();
  const auto drained = subscriber.messages();
  run_cycles(*client, 104, 1);
  ASSERT_TRUE(
      subscriber.wait_for([](const auto& m) { return has_records(m, 5); }, kArrivalTimeout_s));
  daemon->stop(SIGTERM);
  ASSERT_TRUE(subscriber.wait_for(
      [](const auto& all) {
        const auto status = PahoSubscriber::on(all, kTopic + "/status");
        return !status.empty() && testing::field(status.back(), "text") == "offline";
      },
      30.0));
  const auto all = subscriber.messages();

  // Every result once, in order, on both topics, all under the daemon's one boot id.
  const std::vector<int> expected{1, 2, 3, 4, 5};
  EXPECT_EQ(records(all, kTopic + "/result"), expected);
  EXPECT_EQ(records(all, kTopic + "/result/json"), expected);
  const std::string boot = std::to_string(boot_id());
  for (const auto& m : all) {
    if (testing::field(m, "topic").find("/result") == std::string::npos) continue;
    EXPECT_EQ(testing::prop(m, "boot_id"), boot);
    EXPECT_EQ(testing::prop(m, "station"), kStation);
    EXPECT_EQ(testing::prop(m, "result_seq"), testing::prop(m, "record"));  // no wrap yet
  }
  // The protobuf payload is the stored report; the JSON summary says what the report says.
  const auto pb = first_arrivals(all, kTopic + "/result");
  const auto json = first_arrivals(all, kTopic + "/result/json");
  for (int k = 0; k < 5; ++k) {
    const v1::InspectionReport r = report(k + 1);
    EXPECT_EQ(static_cast<std::size_t>(testing::number(pb[k], "size")), r.ByteSizeLong());
    testing::Message summary;
    ASSERT_TRUE(
        google::protobuf::util::JsonStringToMessage(testing::field(json[k], "text"), &summary)
            .ok());
    EXPECT_EQ(testing::field(summary, "schema"), "springscan.result.v1");
    EXPECT_EQ(testing::number(summary, "record"), k + 1);
    EXPECT_EQ(testing::number(summary, "boot_id"), boot_id());
    EXPECT_EQ(testing::number(summary, "job_id"), 100 + k);
    EXPECT_EQ(testing::field(summary, "part_id"), "1");
    EXPECT_EQ(testing::number(summary, "result_code"), 0);
    EXPECT_TRUE(summary.fields().at("pass").bool_value());
    const auto& bends = summary.fields().at("bends").list_value();
    ASSERT_EQ(bends.values_size(), r.bends_size());
    for (int j = 0; j < r.bends_size(); ++j) {
      EXPECT_DOUBLE_EQ(testing::number(bends.values(j).struct_value(), "springback_deg"),
                       r.bends(j).springback_deg());
    }
    EXPECT_DOUBLE_EQ(testing::number(summary.fields().at("deviation").struct_value(), "p95_mm"),
                     r.deviation().p95());
  }
  // The status: retained "online" while the daemon runs, "offline" after its clean stop.
  const auto status = PahoSubscriber::on(all, kTopic + "/status");
  ASSERT_FALSE(status.empty());
  EXPECT_EQ(testing::field(status.front(), "text"), "online");
  // The acknowledged record survives in the store for the next start.
  std::ifstream acked(reports() + "/mqtt_acked_record");
  int last = 0;
  acked >> last;
  EXPECT_EQ(last, 5);

  // Figures: persisted -> received (records published while the broker was up), and the
  // backlog of two results drained after the broker came back.
  double worst_latency = 0.0;
  for (int k : {0, 1, 4}) {
    worst_latency = std::max(worst_latency, testing::number(json[k], "t") - persisted_at(k + 1));
  }
  const double restart_s = std::chrono::duration<double>(restart.time_since_epoch()).count();
  double drain = 0.0;
  for (const auto& m : PahoSubscriber::on(drained, kTopic + "/result/json")) {
    drain = std::max(drain, testing::number(m, "t") - restart_s);
  }
  std::printf("[figure] mqtt publish latency (persisted -> subscriber), worst of 3: %.1f ms\n",
              worst_latency * 1000.0);
  std::printf("[figure] mqtt backlog of 2 results drained %.2f s after the broker restart\n",
              drain);
  RecordProperty("publish_latency_ms", std::to_string(worst_latency * 1000.0));
  RecordProperty("backlog_drain_s", std::to_string(drain));
  EXPECT_EQ(records(before_outage, kTopic + "/result/json"), (std::vector<int>{1, 2}));

  // A restart of the daemon publishes what the broker did not acknowledge: here, as if the
  // acknowledgements of records 4 and 5 had been lost, they come again under a new boot id.
  analysis::write_file_atomically(reports() + "/mqtt_acked_record", "3\n");
  daemon = start_daemon();
  ASSERT_TRUE(
      subscriber.wait_for([](const auto& m) { return has_records(m, 7); }, kArrivalTimeout_s));
  const auto again = subscriber.messages();
  EXPECT_EQ(records(again, kTopic + "/result/json"), (std::vector<int>{1, 2, 3, 4, 5, 4, 5}));
  const auto json_again = first_arrivals(again, kTopic + "/result/json");
  EXPECT_NE(testing::prop(json_again[5], "boot_id"), boot);
  EXPECT_EQ(testing::prop(json_again[5], "boot_id"), std::to_string(boot_id()));
}

/// The CA, and a server certificate for localhost / 127.0.0.1 signed by it, made with openssl.
testing::BrokerTls make_certificates(const std::string& dir) {
  const std::string d = dir + "/";
  const std::string commands[] = {
      "openssl req -x509 -newkey rsa:2048 -nodes -days 2 -subj /CN=springscan-test-ca -keyout " +
          d + "ca.key -out " + d + "ca.crt",
      "openssl req -newkey rsa:2048 -nodes -subj /CN=localhost -keyout " + d + "server.key -out " +
          d + "server.csr",
      "printf 'subjectAltName=DNS:localhost,IP:127.0.0.1\\n' > " + d + "san.ext",
      "openssl x509 -req -in " + d + "server.csr -CA " + d + "ca.crt -CAkey " + d +
          "ca.key -CAcreateserial -days 2 -extfile " + d + "san.ext -out " + d + "server.crt",
  };
  for (const auto& command : commands) {
    const auto [status, output] = testing::run_command(command);
    if (status != 0) throw std::runtime_error(command + ": " + output);
  }
  return {d + "ca.crt", d + "server.crt", d + "server.key"};
}

TEST_F(HilMqttTest, ResultsGoOverTlsToABrokerWithACertificateFromTheTestCa) {
  const testing::BrokerTls tls = make_certificates(broker_dir("pki"));
  testing::MosquittoBroker broker(broker_dir("broker"), /*persistent=*/false, tls);
  PahoSubscriber subscriber(subscriber_script(), dir_.str(), broker.port(), kPrefix,
                            {"--host", "localhost", "--ca-file", tls.ca_file});
  ASSERT_TRUE(subscriber.wait_for(
      [](const auto& m) { return PahoSubscriber::count_events(m, "subscribed") >= 1; }, 30.0));
  std::ofstream(config_path(), std::ios::app)
      << "station_name: \"" << kStation << "\"\nmqtt { host: \"localhost\" port: " << broker.port()
      << " ca_file: \"" << tls.ca_file << "\" retry_max_s: 1 }\n";
  emulate(testing::kGoodSpringback);
  auto daemon = start_daemon();
  auto client = plc(daemon->port());
  wait_online(*client);
  run_cycles(*client, 7, 1);
  ASSERT_TRUE(
      subscriber.wait_for([](const auto& m) { return has_records(m, 1); }, kArrivalTimeout_s))
      << broker.log();
  const auto all = subscriber.messages();
  EXPECT_EQ(records(all, kTopic + "/result"), std::vector<int>{1});
  EXPECT_EQ(records(all, kTopic + "/result/json"), std::vector<int>{1});
  EXPECT_EQ(static_cast<std::size_t>(
                testing::number(PahoSubscriber::on(all, kTopic + "/result")[0], "size")),
            report(1).ByteSizeLong());
}

TEST_F(HilMqttTest, CheckValidatesTheMqttSection) {
  add_mqtt(1883, "ca_file: \"/nonexistent/ca.crt\" ");
  auto [status, output] = testing::run_command(std::string(springscan::test_paths::kSpringscand) +
                                               " --check --config " + config_path());
  EXPECT_NE(status, 0) << output;
  EXPECT_NE(output.find("mqtt.ca_file: '/nonexistent/ca.crt' is not a readable file"),
            std::string::npos)
      << output;
  write_config({});
  add_mqtt(1883);
  std::tie(status, output) = testing::run_command(
      std::string(springscan::test_paths::kSpringscand) + " --check --config " + config_path());
  EXPECT_EQ(status, 0) << output;
}

}  // namespace
}  // namespace springscan::daemon
