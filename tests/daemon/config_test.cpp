#include "daemon/config.hpp"

#include <gtest/gtest.h>

#include <fstream>
#include <regex>
#include <sstream>

#include "test_rig.hpp"
#include "tests/support/test_paths.hpp"

namespace springscan::daemon {
namespace {

using testing::TempDir;

class ConfigTest : public ::testing::Test {
 protected:
  ConfigTest() : dir_("springscan-config") { std::ofstream(dir_.str() + "/part.step") << "x"; }

  analysis::Expected<DaemonSettings> parse(const std::string& text) {
    return parse_daemon_config(text, dir_.str() + "/station.textproto");
  }
  std::string file() const { return dir_.str() + "/station.textproto"; }

  TempDir dir_;
};

constexpr const char* kMinimal = "parts { part_id: 3 cad_file: \"part.step\" }\n";

TEST_F(ConfigTest, DefaultsComeFromTheStructs) {
  auto s = parse(kMinimal);
  ASSERT_TRUE(s.ok()) << s.message();
  const DaemonSettings defaults;
  EXPECT_EQ(s->station.modbus.port, defaults.station.modbus.port);
  EXPECT_EQ(s->station.modbus.port, 502);
  EXPECT_EQ(s->station.word_order, regs::WordOrder::kAbcd);
  EXPECT_DOUBLE_EQ(s->station.machine.plc_heartbeat_timeout_s, 3.0);
  ASSERT_EQ(s->parts.size(), 1u);
  EXPECT_EQ(s->parts[0].cad_file, dir_.str() + "/part.step");  // resolved against the config
  EXPECT_EQ(s->station.machine.known_parts.count(3), 1u);
}

TEST_F(ConfigTest, EveryFieldIsApplied) {
  auto s = parse(R"(
modbus {
  bind_address: "127.0.0.1"
  port: 1502
  allowed_clients: "10.0.0.5"
  allowed_clients: "10.0.0.6"
  unit_id: 17
  word_order: CDAB
  max_connections: 3
  idle_timeout_s: 30
  plc_heartbeat_timeout_s: 0
  partial_frame_timeout_s: 0.25
  trigger_release_timeout_s: 2
  result_ttl_s: 0
  auto_ack_on_trigger: true
}
scanner { kind: LASER_LINE vendor_id: 0x1d50 product_id: 0x6018 serial: "A1" timeout_s: 4 }
parts { part_id: 3 name: "bracket" cad_file: "part.step"
        settings { verdict { angle_tolerance_deg: 0.5 } } }
report_dir: "reports"
report_retention: 50
log_level: "debug"
station_name: "press 4"
)");
  ASSERT_TRUE(s.ok()) << s.message();
  EXPECT_EQ(s->station.modbus.bind_address, "127.0.0.1");
  EXPECT_EQ(s->station.modbus.port, 1502);
  EXPECT_EQ(s->station.modbus.allowed_clients.size(), 2u);
  EXPECT_EQ(s->station.modbus.unit_id, 17);
  EXPECT_EQ(s->station.word_order, regs::WordOrder::kCdab);
  EXPECT_EQ(s->station.modbus.max_connections, 3);
  EXPECT_DOUBLE_EQ(s->station.modbus.partial_frame_timeout_s, 0.25);
  EXPECT_DOUBLE_EQ(s->station.machine.plc_heartbeat_timeout_s, 0.0);
  EXPECT_DOUBLE_EQ(s->station.machine.trigger_release_timeout_s, 2.0);
  EXPECT_TRUE(s->station.machine.auto_ack_on_trigger);
  EXPECT_EQ(s->scanner.product_id(), 0x6018u);
  EXPECT_DOUBLE_EQ(s->parts[0].settings.verdict().angle_tolerance_deg(), 0.5);
  EXPECT_EQ(s->station.reports.directory, dir_.str() + "/reports");
  EXPECT_EQ(s->station.reports.retention, 50);
  EXPECT_EQ(s->log_level, LogLevel::kDebug);
  EXPECT_EQ(s->station.runner.station_name, "press 4");
}

TEST_F(ConfigTest, SyntaxErrorNamesFileLineAndColumn) {
  auto s = parse("modbus {\n  port: 1502\n  prot: 3\n}\n");
  ASSERT_FALSE(s.ok());
  EXPECT_EQ(s.message().rfind(file() + ":3:", 0), 0u) << s.message();
  EXPECT_NE(s.message().find("prot"), std::string::npos);
}

TEST_F(ConfigTest, ValidationErrorNamesLineFieldAndValue) {
  auto s = parse(std::string(kMinimal) + "modbus {\n  port: 70000\n}\n");
  ASSERT_FALSE(s.ok());
  EXPECT_EQ(s.message(), file() + ":3:3: modbus.port: 70000 is not in 0..65535");
}

TEST_F(ConfigTest, BadAllowListEntryNamesItsIndex) {
  auto s = parse(std::string(kMinimal) +
                 "modbus {\n  allowed_clients: \"10.0.0.1\"\n  allowed_clients: \"10.0.0\"\n}\n");
  ASSERT_FALSE(s.ok());
  EXPECT_EQ(s.message(),
            file() + ":4:3: modbus.allowed_clients[1]: '10.0.0' is not an IPv4 address");
}

TEST_F(ConfigTest, PartCatalogueErrors) {
  auto empty = parse("report_dir: \"x\"\n");
  ASSERT_FALSE(empty.ok());
  EXPECT_NE(empty.message().find("part catalogue is empty"), std::string::npos);
  auto duplicate = parse(std::string(kMinimal) + kMinimal);
  ASSERT_FALSE(duplicate.ok());
  EXPECT_NE(duplicate.message().find(":2:9: parts[1].part_id: 3 appears twice"), std::string::npos)
      << duplicate.message();
  auto missing = parse("parts { part_id: 4 cad_file: \"nope.step\" }\n");
  ASSERT_FALSE(missing.ok());
  EXPECT_NE(missing.message().find("parts[0].cad_file: 'nope.step' is not a readable file"),
            std::string::npos)
      << missing.message();
  auto zero = parse("parts { part_id: 0 cad_file: \"part.step\" }\n");
  EXPECT_NE(zero.message().find("parts[0].part_id: 0 is not in 1..65535"), std::string::npos);
}

// check_part { } (docs/calibration.md): its references go to the runner as written.
TEST_F(ConfigTest, CheckPartIsAppliedWithItsReferences) {
  auto none = parse(kMinimal);
  ASSERT_TRUE(none.ok()) << none.message();
  EXPECT_FALSE(none->station.runner.check_part.has_value());
  auto s = parse(std::string(kMinimal) +
                 "check_part { part_id: 3\n"
                 "  reference { characteristic: \"bend 2 springback\" value: 0.4 limit: 0.1 }\n"
                 "  reference { characteristic: \"pose rotation z\" value: 0 limit: 0.05 } }\n");
  ASSERT_TRUE(s.ok()) << s.message();
  ASSERT_TRUE(s->station.runner.check_part.has_value());
  EXPECT_EQ(s->station.runner.check_part->part_id(), 3);
  ASSERT_EQ(s->station.runner.check_part->reference_size(), 2);
  EXPECT_DOUBLE_EQ(s->station.runner.check_part->reference(1).limit(), 0.05);
}

TEST_F(ConfigTest, CheckPartErrorsNameTheField) {
  const auto error = [&](const std::string& section) {
    auto s = parse(std::string(kMinimal) + "check_part {\n" + section + "\n}\n");
    EXPECT_FALSE(s.ok()) << section;
    return s.ok() ? std::string() : s.message();
  };
  const std::string ref = "part_id: 3 reference { characteristic: \"bend 1 springback\" ";
  EXPECT_NE(error("part_id: 4").find("check_part.part_id: 4 is not a part_id of the catalogue"),
            std::string::npos);
  EXPECT_NE(error("part_id: 3").find("check_part: no reference"), std::string::npos);
  EXPECT_NE(error(ref + "value: 0.4 limit: 0 }").find("reference[0].limit: 0 is not a positive"),
            std::string::npos);
  EXPECT_NE(error(ref + "value: nan limit: 0.1 }").find("reference[0].value: nan is not a number"),
            std::string::npos);
  EXPECT_NE(error("part_id: 3 reference { value: 1 limit: 1 }")
                .find("check_part.reference[0].characteristic: is empty"),
            std::string::npos);
  EXPECT_NE(error(ref + "value: 0.4 limit: 0.1 }\n" + ref.substr(11) + "value: 0.5 limit: 0.1 }")
                .find("reference[1].characteristic: 'bend 1 springback' appears twice"),
            std::string::npos);
}

// Paths the filesystem refuses to look at (found by fuzz_daemon_config: a 4 KB cad_file made
// std::filesystem throw ENAMETOOLONG out of the parser): each is a clear config error naming
// its field, for the part catalogue and for the MQTT files alike.
TEST_F(ConfigTest, PathsTheFilesystemRefusesAreConfigErrors) {
  const std::string too_long(5000, 'a');
  const std::string through_a_file = "part.step/inside.step";  // a component that is a file
  for (const std::string& path : {too_long, through_a_file}) {
    auto part = parse("parts { part_id: 4 cad_file: \"" + path + "\" }\n");
    ASSERT_FALSE(part.ok());
    EXPECT_NE(part.message().find("parts[0].cad_file: '" + path + "' is not a readable file"),
              std::string::npos)
        << part.message();
    auto mqtt = parse(std::string(kMinimal) + "mqtt { ca_file: \"" + path + "\" }\n");
    ASSERT_FALSE(mqtt.ok());
    EXPECT_NE(mqtt.message().find("mqtt.ca_file: '" + path + "' is not a readable file"),
              std::string::npos)
        << mqtt.message();
  }
}

TEST_F(ConfigTest, OtherRangeErrors) {
  EXPECT_NE(parse(std::string(kMinimal) + "log_level: \"loud\"")
                .message()
                .find("log_level: 'loud' is not one of"),
            std::string::npos);
  EXPECT_NE(parse(std::string(kMinimal) + "modbus { unit_id: 0 }")
                .message()
                .find("modbus.unit_id: 0 is not in 1..247"),
            std::string::npos);
  EXPECT_NE(parse(std::string(kMinimal) + "modbus { max_connections: 500 }")
                .message()
                .find("modbus.max_connections: 500"),
            std::string::npos);
  EXPECT_NE(parse(std::string(kMinimal) + "report_retention: 0")
                .message()
                .find("report_retention: 0 is not in"),
            std::string::npos);
  EXPECT_NE(parse(std::string(kMinimal) + "scanner { vendor_id: 70000 }")
                .message()
                .find("scanner: scanner.vendor_id = 70000 (1..65535)"),
            std::string::npos);
}

TEST_F(ConfigTest, MqttIsOffByDefaultAndOnWithItsSection) {
  auto off = parse(std::string(kMinimal) + "station_name: \"press-2\"\n");
  ASSERT_TRUE(off.ok()) << off.message();
  EXPECT_FALSE(off->mqtt.enabled);
  EXPECT_EQ(off->mqtt.station, "press-2");  // the topic's station defaults to station_name
  std::ofstream(dir_.str() + "/ca.crt") << "x";
  std::ofstream(dir_.str() + "/password") << "secret\n";
  auto on = parse(std::string(kMinimal) + R"(mqtt {
  host: "broker.plant" port: 8883 client_id: "p2" topic_prefix: "plant/springscan/v1"
  station: "p-2" ca_file: "ca.crt" username: "station" password_file: "password"
  keepalive_s: 20 retry_max_s: 60
})");
  ASSERT_TRUE(on.ok()) << on.message();
  const MqttSettings& m = on->mqtt;
  EXPECT_TRUE(m.enabled);
  EXPECT_EQ(m.host, "broker.plant");
  EXPECT_EQ(m.port, 8883);
  EXPECT_EQ(m.client_id, "p2");
  EXPECT_EQ(m.station, "p-2");
  EXPECT_EQ(m.ca_file, dir_.str() + "/ca.crt");  // resolved against the config
  EXPECT_EQ(m.password_file, dir_.str() + "/password");
  EXPECT_EQ(m.keepalive_s, 20);
  EXPECT_DOUBLE_EQ(m.retry_max_s, 60.0);
  EXPECT_EQ(mqtt_topics(m).json, "plant/springscan/v1/p-2/result/json");
  auto disabled = parse(std::string(kMinimal) + "mqtt { enabled: false }");
  ASSERT_TRUE(disabled.ok());
  EXPECT_FALSE(disabled->mqtt.enabled);
}

TEST_F(ConfigTest, MqttErrorsNameTheField) {
  const auto error = [this](const std::string& mqtt) {
    return parse(std::string(kMinimal) + "mqtt {\n  " + mqtt + "\n}\n").message();
  };
  EXPECT_EQ(error("port: 0"), file() + ":3:3: mqtt.port: 0 is not in 1..65535");
  EXPECT_EQ(error("port: 70000"), file() + ":3:3: mqtt.port: 70000 is not in 1..65535");
  EXPECT_EQ(error("ca_file: \"none.crt\""),
            file() + ":3:3: mqtt.ca_file: 'none.crt' is not a readable file (resolved to " +
                dir_.str() + "/none.crt)");
  EXPECT_NE(error("station: \"a/b\"").find("mqtt.station: 'a/b' cannot be a topic level"),
            std::string::npos);
  EXPECT_NE(error("topic_prefix: \"plant/#\"").find("mqtt.topic_prefix: 'plant/#'"),
            std::string::npos);
  std::ofstream(dir_.str() + "/c.crt") << "x";
  EXPECT_NE(error("cert_file: \"c.crt\"").find("cert_file and key_file go together"),
            std::string::npos);
  std::ofstream(dir_.str() + "/password") << "x";
  EXPECT_NE(error("password_file: \"password\"").find("a password needs a username"),
            std::string::npos);
  EXPECT_NE(error("host: \"\"").find("mqtt.host: is empty"), std::string::npos);
}

// The operator page (docs/operator-page.md): off without its section, 127.0.0.1 by default.
TEST_F(ConfigTest, HttpIsOffByDefaultAndOnWithItsSection) {
  auto off = parse(kMinimal);
  ASSERT_TRUE(off.ok()) << off.message();
  EXPECT_FALSE(off->http.enabled);
  auto on = parse(std::string(kMinimal) + "http { port: 8081 shift_starts: \"07:30\" }\n");
  ASSERT_TRUE(on.ok()) << on.message();
  EXPECT_TRUE(on->http.enabled);
  EXPECT_EQ(on->http.address, "127.0.0.1");
  EXPECT_EQ(on->http.port, 8081);
  EXPECT_EQ(on->http.shift_starts_min, std::vector<int>{7 * 60 + 30});
  EXPECT_FALSE(parse(std::string(kMinimal) + "http { enabled: false }\n")->http.enabled);
}

TEST_F(ConfigTest, HttpErrorsNameTheField) {
  const std::pair<const char*, const char*> cases[] = {
      {"http { address: \"localhost\" }", "http.address: 'localhost' is not an IPv4 address"},
      {"http { port: 70000 }", "http.port: 70000 is not in 0..65535"},
      {"http { max_clients: 0 }", "http.max_clients: 0 is not in 1..1000"},
      {"http { shift_starts: \"06:00\" shift_starts: \"25:00\" }",
       "http.shift_starts[1]: '25:00' is not a time of day HH:MM"},
  };
  for (const auto& [text, expected] : cases) {
    auto s = parse(std::string(kMinimal) + text + "\n");
    ASSERT_FALSE(s.ok()) << text;
    EXPECT_NE(s.message().find(expected), std::string::npos) << s.message();
  }
}

TEST_F(ConfigTest, MissingFileIsAnError) {
  auto s = load_daemon_config(dir_.str() + "/absent.textproto");
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.message().find("absent.textproto: cannot read"), std::string::npos);
}

TEST_F(ConfigTest, ShippedConfigParses) {
  // The shipped file names production CAD paths; point them at the test part.
  std::ifstream in(springscan::test_paths::source("config/springscand.textproto"));
  ASSERT_TRUE(in.good());
  std::stringstream text;
  text << in.rdbuf();
  const std::string local =
      std::regex_replace(text.str(), std::regex("cad_file: \"[^\"]*\""), "cad_file: \"part.step\"");
  auto s = parse(local);
  ASSERT_TRUE(s.ok()) << s.message();
  EXPECT_GE(s->parts.size(), 1u);
}

}  // namespace
}  // namespace springscan::daemon
