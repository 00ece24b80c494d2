// Conversion of the DaemonConfig text proto into DaemonSettings (STYLE.md section 1: only
// *_proto.cpp files convert between proto messages and our structs).
#include <arpa/inet.h>
#include <google/protobuf/io/tokenizer.h>
#include <google/protobuf/text_format.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <system_error>
#include <utility>

#include "daemon/config.hpp"
#include "drivers/scanner_proto.hpp"

namespace springscan::daemon {

namespace fs = std::filesystem;
using analysis::Expected;
using analysis::fail;
using google::protobuf::TextFormat;

namespace {

/// Collects the parser's first error with its position (lines and columns are 0-based there).
class FirstError : public google::protobuf::io::ErrorCollector {
 public:
  void AddError(int line, google::protobuf::io::ColumnNumber column,
                const std::string& message) override {
    if (!message_.empty()) return;
    message_ = std::to_string(line + 1) + ":" + std::to_string(column + 1) + ": " + message;
  }
  const std::string& message() const { return message_; }

 private:
  std::string message_;
};

/// Turns a field path into "file:line:column: modbus.port" using the parser's locations.
class Locator {
 public:
  using Path = std::vector<std::pair<const char*, int>>;  // field name, index (-1: singular)
  Locator(std::string file, const TextFormat::ParseInfoTree& tree)
      : file_(std::move(file)), tree_(tree) {}

  std::string where(const Path& path) const {
    const google::protobuf::Descriptor* type = v1::DaemonConfig::descriptor();
    const TextFormat::ParseInfoTree* tree = &tree_;
    std::string name;
    TextFormat::ParseLocation location;
    for (std::size_t i = 0; i < path.size(); ++i) {
      const auto* field = type != nullptr ? type->FindFieldByName(path[i].first) : nullptr;
      if (i > 0) name.push_back('.');
      name.append(path[i].first);
      if (path[i].second >= 0) {
        name.push_back('[');
        name.append(std::to_string(path[i].second));
        name.push_back(']');
      }
      if (field == nullptr || tree == nullptr) continue;
      if (i + 1 == path.size()) {
        location = tree->GetLocation(field, path[i].second);
      } else {
        location = tree->GetLocation(field, path[i].second);
        tree = tree->GetTreeForNested(field, path[i].second);
        type = field->message_type();
      }
    }
    std::string prefix = file_;
    if (location.line >= 0) {
      prefix.push_back(':');
      prefix.append(std::to_string(location.line + 1));
      prefix.push_back(':');
      prefix.append(std::to_string(location.column + 1));
    }
    prefix.append(": ");
    prefix.append(name);
    return prefix;
  }

 private:
  std::string file_;
  const TextFormat::ParseInfoTree& tree_;
};

bool ipv4(const std::string& text) {
  in_addr addr{};
  return inet_pton(AF_INET, text.c_str(), &addr) == 1;
}

std::string number(double value) {
  std::ostringstream out;
  out << value;
  return out.str();
}

/// Fails with "where: value is not in lo..hi" unless lo <= value <= hi.
template <typename T>
std::string out_of_range(const Locator& at, const Locator::Path& path, T value, T lo, T hi) {
  if (value >= lo && value <= hi) return "";
  return at.where(path) + ": " + number(static_cast<double>(value)) + " is not in " +
         number(static_cast<double>(lo)) + ".." + number(static_cast<double>(hi));
}

// True for a regular file. The non-throwing form: a path the filesystem refuses (too long, a
// component that is a file, no permission) is simply not a file here, never an exception
// (found by fuzz_daemon_config: a 4 KB cad_file made is_regular_file throw ENAMETOOLONG).
bool is_file(const std::string& path) {
  std::error_code ec;
  return fs::is_regular_file(path, ec) && !ec;
}

std::string resolve(const std::string& path, const std::string& config_file) {
  if (path.empty() || fs::path(path).is_absolute()) return path;
  return (fs::path(config_file).parent_path() / path).lexically_normal().string();
}

// One field after the other, each checked with its range (about 65 lines: a list, not logic).
std::string apply_modbus(const v1::ModbusConfig& m, const Locator& at, DaemonSettings& out) {
  ModbusServerSettings& s = out.station.modbus;
  MachineSettings& machine = out.station.machine;
  if (m.has_bind_address()) {
    if (!ipv4(m.bind_address())) {
      return at.where({{"modbus", -1}, {"bind_address", -1}}) + ": '" + m.bind_address() +
             "' is not an IPv4 address";
    }
    s.bind_address = m.bind_address();
  }
  for (int i = 0; i < m.allowed_clients_size(); ++i) {
    if (!ipv4(m.allowed_clients(i))) {
      return at.where({{"modbus", -1}, {"allowed_clients", i}}) + ": '" + m.allowed_clients(i) +
             "' is not an IPv4 address";
    }
    s.allowed_clients.push_back(m.allowed_clients(i));
  }
  for (int i = 0; i < m.plc_clients_size(); ++i) {
    if (!ipv4(m.plc_clients(i))) {
      return at.where({{"modbus", -1}, {"plc_clients", i}}) + ": '" + m.plc_clients(i) +
             "' is not an IPv4 address";
    }
    s.plc_clients.push_back(m.plc_clients(i));
  }
  std::string e;
  const auto path = [](const char* field) { return Locator::Path{{"modbus", -1}, {field, -1}}; };
  if (m.has_port() && !(e = out_of_range(at, path("port"), m.port(), 0, 65535)).empty()) return e;
  if (m.has_port()) s.port = m.port();
  if (m.has_unit_id()) {
    if (m.unit_id() != 255 &&
        !(e = out_of_range(at, path("unit_id"), m.unit_id(), 1, 247)).empty()) {
      return e;
    }
    s.unit_id = static_cast<std::uint8_t>(m.unit_id());
  }
  if (m.has_word_order()) {
    out.station.word_order =
        m.word_order() == v1::ModbusConfig::CDAB ? regs::WordOrder::kCdab : regs::WordOrder::kAbcd;
  }
  if (m.has_max_connections()) {
    // libmodbus select()s on each client: keep the count small (notes section 2).
    if (!(e = out_of_range(at, path("max_connections"), m.max_connections(), 1, 16)).empty()) {
      return e;
    }
    s.max_connections = m.max_connections();
  }
  if (m.has_max_connections_per_address()) {
    if (!(e = out_of_range(at, path("max_connections_per_address"), m.max_connections_per_address(),
                           0, 16))
             .empty()) {
      return e;
    }
    s.max_connections_per_address = m.max_connections_per_address();
  }
  struct Seconds {
    const char* name;
    bool present;
    double value;
    double lo, hi;
    double* target;
  };
  const Seconds seconds[] = {
      {"idle_timeout_s", m.has_idle_timeout_s(), m.idle_timeout_s(), 1, 86400, &s.idle_timeout_s},
      {"partial_frame_timeout_s", m.has_partial_frame_timeout_s(), m.partial_frame_timeout_s(),
       0.01, 10, &s.partial_frame_timeout_s},
      {"plc_heartbeat_timeout_s", m.has_plc_heartbeat_timeout_s(), m.plc_heartbeat_timeout_s(), 0,
       3600, &machine.plc_heartbeat_timeout_s},
      {"trigger_release_timeout_s", m.has_trigger_release_timeout_s(),
       m.trigger_release_timeout_s(), 0.1, 3600, &machine.trigger_release_timeout_s},
      {"result_ttl_s", m.has_result_ttl_s(), m.result_ttl_s(), 0, 86400, &machine.result_ttl_s},
  };
  for (const Seconds& field : seconds) {
    if (!field.present) continue;
    if (!(e = out_of_range(at, path(field.name), field.value, field.lo, field.hi)).empty()) {
      return e;
    }
    *field.target = field.value;
  }
  if (m.has_auto_ack_on_trigger()) machine.auto_ack_on_trigger = m.auto_ack_on_trigger();
  return "";
}

std::string apply_parts(const v1::DaemonConfig& c, const Locator& at, const std::string& file,
                        DaemonSettings& out) {
  if (c.parts_size() == 0) return file + ": parts: the part catalogue is empty (add a parts { })";
  std::set<int> seen;
  for (int i = 0; i < c.parts_size(); ++i) {
    const v1::PartConfig& p = c.parts(i);
    std::string e = out_of_range(at, {{"parts", i}, {"part_id", -1}}, p.part_id(), 1, 65535);
    if (!e.empty()) return e;
    if (!seen.insert(p.part_id()).second) {
      return at.where({{"parts", i}, {"part_id", -1}}) + ": " + std::to_string(p.part_id()) +
             " appears twice in the catalogue";
    }
    const std::string cad = resolve(p.cad_file(), file);
    if (cad.empty() || !is_file(cad)) {
      return at.where({{"parts", i}, {"cad_file", -1}}) + ": '" + p.cad_file() +
             "' is not a readable file" + (cad != p.cad_file() ? " (resolved to " + cad + ")" : "");
    }
    // The same validation the analysis runs, now rather than as a FAULT at the first trigger.
    if (auto valid = analysis::check_analysis_settings(p.settings()); !valid) {
      return at.where({{"parts", i}, {"settings", -1}}) + ": " + valid.message();
    }
    out.station.machine.known_parts.insert(static_cast<std::uint16_t>(p.part_id()));
    out.parts.push_back(
        PartEntry{static_cast<std::uint16_t>(p.part_id()), p.name(), cad, p.settings()});
  }
  return "";
}

Locator::Path check_path(int reference, const char* field) {
  return Locator::Path{{"check_part", -1}, {"reference", reference}, {field, -1}};
}

// check_part { part_id reference { characteristic value limit } }: a part of the catalogue,
// references with finite values and positive limits, each characteristic once.
std::string apply_check_part(const v1::DaemonConfig& c, const Locator& at, DaemonSettings& out) {
  if (!c.has_check_part()) return "";
  const v1::CheckPartConfig& check = c.check_part();
  const Locator::Path id{{"check_part", -1}, {"part_id", -1}};
  if (check.part_id() < 1 || check.part_id() > 65535 ||
      out.station.machine.known_parts.count(static_cast<std::uint16_t>(check.part_id())) == 0)
    return at.where(id) + ": " + std::to_string(check.part_id()) +
           " is not a part_id of the catalogue (parts { }): the check part is inspected as a part";
  if (check.reference_size() == 0)
    return at.where({{"check_part", -1}}) + ": no reference { characteristic value limit }";
  std::set<std::string> seen;
  for (int i = 0; i < check.reference_size(); ++i) {
    const v1::CheckReference& r = check.reference(i);
    if (r.characteristic().empty()) return at.where(check_path(i, "characteristic")) + ": is empty";
    if (!seen.insert(r.characteristic()).second)
      return at.where(check_path(i, "characteristic")) + ": '" + r.characteristic() +
             "' appears twice";
    if (!std::isfinite(r.value()))
      return at.where(check_path(i, "value")) + ": " + number(r.value()) + " is not a number";
    if (!(r.limit() > 0.0) || !std::isfinite(r.limit()))
      return at.where(check_path(i, "limit")) + ": " + number(r.limit()) +
             " is not a positive number";
  }
  out.station.runner.check_part = check;
  return "";
}

std::string apply_top_level(const v1::DaemonConfig& c, const Locator& at, const std::string& file,
                            DaemonSettings& out) {
  const v1::ScannerConfig& sc = c.scanner();
  // The scanner section is checked by the driver's own conversion, the one place that knows its
  // fields and ranges (drivers/scanner_proto.hpp); main() builds the driver from the same
  // message with drivers::make_scanner.
  if (auto checked = drivers::check_scanner_config(sc); !checked) {
    return at.where({{"scanner", -1}}) + ": " + checked.message();
  }
  out.scanner = sc;
  std::string e;
  if (c.has_report_dir()) {
    if (c.report_dir().empty()) return at.where({{"report_dir", -1}}) + ": is empty";
    out.station.reports.directory = resolve(c.report_dir(), file);
  }
  if (c.has_report_retention()) {
    e = out_of_range(at, {{"report_retention", -1}}, c.report_retention(), 1, 10000000);
    if (!e.empty()) return e;
    out.station.reports.retention = c.report_retention();
  }
  if (c.has_model_cache_dir()) out.model_cache_dir = resolve(c.model_cache_dir(), file);
  if (c.has_log_level()) {
    const auto level = parse_log_level(c.log_level());
    if (!level) {
      return at.where({{"log_level", -1}}) + ": '" + c.log_level() +
             "' is not one of debug, info, warning, error";
    }
    out.log_level = *level;
  }
  if (c.has_station_name()) out.station.runner.station_name = c.station_name();
  return "";
}

Locator::Path mqtt_path(const char* field) { return Locator::Path{{"mqtt", -1}, {field, -1}}; }

// mqtt { host port keepalive_s retry_max_s client_id }: where the broker is and how to reach it.
std::string apply_mqtt_connection(const v1::MqttConfig& m, const Locator& at, MqttSettings& s) {
  std::string e;
  if (m.has_host()) {
    if (m.host().empty()) return at.where(mqtt_path("host")) + ": is empty";
    s.host = m.host();
  }
  if (m.has_port() && !(e = out_of_range(at, mqtt_path("port"), m.port(), 1, 65535)).empty()) {
    return e;
  }
  if (m.has_port()) s.port = m.port();
  if (m.has_keepalive_s() &&
      !(e = out_of_range(at, mqtt_path("keepalive_s"), m.keepalive_s(), 5, 3600)).empty()) {
    return e;
  }
  if (m.has_keepalive_s()) s.keepalive_s = m.keepalive_s();
  if (m.has_retry_max_s() &&
      !(e = out_of_range(at, mqtt_path("retry_max_s"), m.retry_max_s(), 0.1, 3600.0)).empty()) {
    return e;
  }
  if (m.has_retry_max_s()) {
    s.retry_max_s = m.retry_max_s();
    s.retry_initial_s = std::min(s.retry_initial_s, s.retry_max_s);
  }
  if (m.has_client_id()) s.client_id = m.client_id();
  return "";
}

// mqtt { topic_prefix station }: topic levels, no wildcards, and the station is one level.
std::string apply_mqtt_topics(const v1::MqttConfig& m, const Locator& at, MqttSettings& s) {
  const auto bad_topic = [](const std::string& text, bool one_level) {
    return text.empty() || text.find_first_of(one_level ? "+#/" : "+#") != std::string::npos ||
           text.front() == '/' || text.back() == '/';
  };
  if (m.has_topic_prefix()) {
    if (bad_topic(m.topic_prefix(), false)) {
      return at.where(mqtt_path("topic_prefix")) + ": '" + m.topic_prefix() +
             "' must be non-empty, without + or # and without a leading or trailing /";
    }
    s.topic_prefix = m.topic_prefix();
  }
  if (m.has_station()) s.station = m.station();
  if (bad_topic(s.station, true)) {
    return (m.has_station() ? at.where(mqtt_path("station")) : at.where({{"station_name", -1}})) +
           ": '" + s.station + "' cannot be a topic level (non-empty, no /, + or #)";
  }
  return "";
}

// mqtt { ca_file cert_file key_file username password_file }: readable now, and in pairs that
// make sense, so that `springscand --check` catches a missing certificate before the service
// starts.
std::string apply_mqtt_credentials(const v1::MqttConfig& m, const Locator& at,
                                   const std::string& file, MqttSettings& s) {
  struct FileField {
    const char* name;
    bool present;
    const std::string& value;
    std::string* target;
  };
  const FileField files[] = {
      {"ca_file", m.has_ca_file(), m.ca_file(), &s.ca_file},
      {"cert_file", m.has_cert_file(), m.cert_file(), &s.cert_file},
      {"key_file", m.has_key_file(), m.key_file(), &s.key_file},
      {"password_file", m.has_password_file(), m.password_file(), &s.password_file}};
  for (const FileField& f : files) {
    if (!f.present) continue;
    const std::string resolved = resolve(f.value, file);
    std::ifstream readable(resolved);
    if (resolved.empty() || !is_file(resolved) || !readable) {
      return at.where(mqtt_path(f.name)) + ": '" + f.value + "' is not a readable file" +
             (resolved != f.value ? " (resolved to " + resolved + ")" : "");
    }
    *f.target = resolved;
  }
  if (s.cert_file.empty() != s.key_file.empty()) {
    return at.where(mqtt_path(s.cert_file.empty() ? "key_file" : "cert_file")) +
           ": cert_file and key_file go together (a TLS client certificate and its key)";
  }
  if (!s.cert_file.empty() && s.ca_file.empty()) {
    return at.where(mqtt_path("cert_file")) + ": a client certificate needs TLS: set ca_file too";
  }
  if (m.has_username()) s.username = m.username();
  if (!s.password_file.empty() && s.username.empty()) {
    return at.where(mqtt_path("password_file")) + ": a password needs a username";
  }
  return "";
}

/// The mqtt { } section: on when present (unless enabled: false).
std::string apply_mqtt(const v1::DaemonConfig& c, const Locator& at, const std::string& file,
                       DaemonSettings& out) {
  MqttSettings& s = out.mqtt;
  if (s.station.empty()) s.station = out.station.runner.station_name;
  if (!c.has_mqtt()) return "";
  const v1::MqttConfig& m = c.mqtt();
  s.enabled = !m.has_enabled() || m.enabled();
  std::string e;
  if (!(e = apply_mqtt_connection(m, at, s)).empty()) return e;
  if (!(e = apply_mqtt_topics(m, at, s)).empty()) return e;
  return apply_mqtt_credentials(m, at, file, s);
}

Locator::Path http_path(const char* field, int index = -1) {
  return Locator::Path{{"http", -1}, {field, index}};
}

// "06:00" -> 360; -1 when it is not a time of day.
int minutes_of_day(const std::string& text) {
  int hours = 0, minutes = 0;
  char end = 0;
  if (text.size() != 5 || std::sscanf(text.c_str(), "%2d:%2d%c", &hours, &minutes, &end) != 2 ||
      hours < 0 || hours > 23 || minutes < 0 || minutes > 59) {
    return -1;
  }
  return hours * 60 + minutes;
}

/// The http { } section (the operator page, docs/operator-page.md): on when present (unless
/// enabled: false).
std::string apply_http(const v1::DaemonConfig& c, const Locator& at, DaemonSettings& out) {
  if (!c.has_http()) return "";
  const v1::HttpConfig& h = c.http();
  PageSettings& s = out.http;
  s.enabled = !h.has_enabled() || h.enabled();
  if (h.has_address()) {
    if (!ipv4(h.address())) {
      return at.where(http_path("address")) + ": '" + h.address() + "' is not an IPv4 address";
    }
    s.address = h.address();
  }
  std::string e;
  if (h.has_port() && !(e = out_of_range(at, http_path("port"), h.port(), 0, 65535)).empty())
    return e;
  if (h.has_port()) s.port = h.port();
  if (h.has_max_clients() &&
      !(e = out_of_range(at, http_path("max_clients"), h.max_clients(), 1, 1000)).empty())
    return e;
  if (h.has_max_clients()) s.max_clients = h.max_clients();
  if (h.has_write_timeout_ms() &&
      !(e = out_of_range(at, http_path("write_timeout_ms"), h.write_timeout_ms(), 100, 60000))
           .empty())
    return e;
  if (h.has_write_timeout_ms()) s.write_timeout_ms = h.write_timeout_ms();
  if (h.shift_starts_size() > 0) s.shift_starts_min.clear();
  for (int i = 0; i < h.shift_starts_size(); ++i) {
    const int minutes = minutes_of_day(h.shift_starts(i));
    if (minutes < 0) {
      return at.where(http_path("shift_starts", i)) + ": '" + h.shift_starts(i) +
             "' is not a time of day HH:MM";
    }
    s.shift_starts_min.push_back(minutes);
  }
  return "";
}

}  // namespace

Expected<DaemonSettings> parse_daemon_config(const std::string& text,
                                             const std::string& file_name) {
  v1::DaemonConfig config;
  TextFormat::Parser parser;
  FirstError errors;
  TextFormat::ParseInfoTree tree;
  parser.RecordErrorsTo(&errors);
  parser.WriteLocationsTo(&tree);
  if (!parser.ParseFromString(text, &config)) {
    return fail(file_name + ":" +
                (errors.message().empty() ? "1:1: parse error" : errors.message()));
  }
  const Locator at(file_name, tree);
  DaemonSettings settings;
  std::string error = apply_modbus(config.modbus(), at, settings);
  if (error.empty()) error = apply_parts(config, at, file_name, settings);
  if (error.empty()) error = apply_check_part(config, at, settings);
  if (error.empty()) error = apply_top_level(config, at, file_name, settings);
  if (error.empty()) error = apply_mqtt(config, at, file_name, settings);
  if (error.empty()) error = apply_http(config, at, settings);
  if (!error.empty()) return fail(error);
  return settings;
}

Expected<DaemonSettings> load_daemon_config(const std::string& path) {
  std::ifstream in(path);
  if (!in) return fail(path + ": cannot read the config file");
  std::ostringstream text;
  text << in.rdbuf();
  return parse_daemon_config(text.str(), path);
}

}  // namespace springscan::daemon
