#include "daemon/result_publisher.hpp"

#include <mosquitto.h>
#include <mqtt_protocol.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <sstream>

#include "analysis/io/file_io.hpp"
#include "daemon/result_summary.hpp"

namespace springscan::daemon {

namespace fs = std::filesystem;
using analysis::Expected;
using analysis::fail;
using Steady = std::chrono::steady_clock;

namespace {

constexpr const char* kAckedFile = "mqtt_acked_record";
constexpr auto kSaveEvery = std::chrono::milliseconds(500);  // while a backlog drains
constexpr auto kOfflineTimeout = std::chrono::seconds(1);    // stop: wait for its PUBACK

/// A libmosquitto return code as words. MOSQ_ERR_ERRNO means "see errno", which is read here,
/// right after the call that returned it (libmosquitto's contract).
std::string describe(int rc, int saved_errno) {
  std::string text = rc == MOSQ_ERR_ERRNO ? std::strerror(saved_errno) : mosquitto_strerror(rc);
  if (rc == MOSQ_ERR_TLS) text = "TLS handshake failed (check ca_file and the broker certificate)";
  if (rc == MOSQ_ERR_CONN_LOST) text = "the broker closed the connection or the network dropped";
  if (rc == MOSQ_ERR_KEEPALIVE) text = "no answer from the broker within the keep-alive";
  if (!text.empty()) text[0] = static_cast<char>(std::tolower(static_cast<unsigned char>(text[0])));
  while (!text.empty() && (text.back() == '.' || text.back() == '\n')) text.pop_back();
  return text;
}

std::string results_waiting(std::uint64_t n) {
  return std::to_string(n) + (n == 1 ? " result waiting" : " results waiting");
}

std::string seconds_text(double s) {
  std::ostringstream out;
  out << s;
  return out.str();
}

/// Owns a property list (mosquitto_property_free_all on destruction).
struct Properties {
  mosquitto_property* list = nullptr;
  Properties() = default;
  Properties(const Properties&) = delete;
  Properties& operator=(const Properties&) = delete;
  ~Properties() { mosquitto_property_free_all(&list); }
  void user(const char* name, const std::string& value) {
    mosquitto_property_add_string_pair(&list, MQTT_PROP_USER_PROPERTY, name, value.c_str());
  }
};

/// "r000000000042" -> 42; anything else -> 0 (the report store's record directories).
std::uint64_t record_number(const std::string& name) {
  if (name.size() != 13 || name[0] != 'r') return 0;
  std::uint64_t value = 0;
  for (std::size_t i = 1; i < name.size(); ++i) {
    if (name[i] < '0' || name[i] > '9') return 0;
    value = value * 10 + static_cast<std::uint64_t>(name[i] - '0');
  }
  return value;
}

}  // namespace

MosquittoLibrary::MosquittoLibrary() { mosquitto_lib_init(); }
MosquittoLibrary::~MosquittoLibrary() { mosquitto_lib_cleanup(); }

void ResultPublisher::MosquittoDeleter::operator()(mosquitto* m) const { mosquitto_destroy(m); }

MqttTopics mqtt_topics(const MqttSettings& settings) {
  const std::string base = settings.topic_prefix + "/" + settings.station;
  return MqttTopics{base + "/result", base + "/result/json", base + "/status"};
}

ResultPublisher::ResultPublisher(const MqttSettings& settings, const ReportStore& store,
                                 std::uint16_t boot_id, Log& log)
    : settings_(settings),
      topics_(mqtt_topics(settings)),
      store_(store),
      boot_id_(boot_id),
      log_(log),
      acked_path_((fs::path(store.record_path(1)).parent_path() / kAckedFile).string()) {}

Expected<std::unique_ptr<ResultPublisher>> ResultPublisher::start(const MqttSettings& settings,
                                                                  const ReportStore& store,
                                                                  std::uint16_t boot_id, Log& log) {
  if (settings.station.empty()) return fail("mqtt.station: is empty");
  std::unique_ptr<ResultPublisher> publisher(new ResultPublisher(settings, store, boot_id, log));
  auto configured = publisher->configure();
  if (!configured) return configured.error();
  publisher->thread_ = std::thread([p = publisher.get()] { p->run(); });
  return publisher;
}

ResultPublisher::~ResultPublisher() {
  {
    std::lock_guard lock(mutex_);
    stop_ = true;
  }
  wake_.notify_all();
  if (thread_.joinable()) thread_.join();
}

Expected<bool> ResultPublisher::configure() {
  const std::string client_id =
      settings_.client_id.empty() ? "springscand-" + settings_.station : settings_.client_id;
  mosq_.reset(mosquitto_new(client_id.c_str(), true, this));
  if (!mosq_) return fail("mqtt: cannot create the MQTT client (out of memory?)");
  mosquitto* m = mosq_.get();
  mosquitto_int_option(m, MOSQ_OPT_PROTOCOL_VERSION, MQTT_PROTOCOL_V5);
  mosquitto_connect_v5_callback_set(
      m, [](mosquitto*, void* self, int rc, int, const mosquitto_property*) {
        static_cast<ResultPublisher*>(self)->on_connack(rc);
      });
  mosquitto_publish_v5_callback_set(
      m, [](mosquitto*, void* self, int mid, int rc, const mosquitto_property*) {
        static_cast<ResultPublisher*>(self)->on_puback(mid, rc);
      });
  const char offline[] = "offline";
  int rc = mosquitto_will_set_v5(m, topics_.status.c_str(), static_cast<int>(sizeof offline - 1),
                                 offline, 1, true, nullptr);
  if (rc != MOSQ_ERR_SUCCESS) {
    return fail("mqtt: topic " + topics_.status + ": " + describe(rc, errno));
  }
  if (!settings_.ca_file.empty()) {
    rc = mosquitto_tls_set(m, settings_.ca_file.c_str(), nullptr,
                           settings_.cert_file.empty() ? nullptr : settings_.cert_file.c_str(),
                           settings_.key_file.empty() ? nullptr : settings_.key_file.c_str(),
                           nullptr);
    if (rc != MOSQ_ERR_SUCCESS) {
      return fail("mqtt TLS (ca_file " + settings_.ca_file + ", cert_file " + settings_.cert_file +
                  "): " + describe(rc, errno));
    }
  }
  if (!settings_.username.empty()) {
    std::string password;
    if (!settings_.password_file.empty()) {
      auto bytes = analysis::read_file_bytes(settings_.password_file);
      if (!bytes) return bytes.error().prepend("mqtt.password_file: ");
      password = bytes->substr(0, bytes->find_first_of("\r\n"));
    }
    rc = mosquitto_username_pw_set(m, settings_.username.c_str(),
                                   settings_.password_file.empty() ? nullptr : password.c_str());
    if (rc != MOSQ_ERR_SUCCESS) return fail("mqtt.username: " + describe(rc, errno));
  }
  // The last acknowledged record of the previous run; a store that was emptied since (its
  // newest record is older) starts over from its first record.
  if (auto text = analysis::read_file_bytes(acked_path_)) {
    std::uint64_t value = 0;
    std::istringstream(*text) >> value;
    if (value > store_.last_record()) {
      log_.warning("MQTT: " + acked_path_ + " says record " + std::to_string(value) +
                   " was published, but the report store ends at record " +
                   std::to_string(store_.last_record()) + "; publishing the whole store");
      value = 0;
    }
    acked_ = value;
  }
  saved_acked_ = acked_.load();
  next_record_ = acked_.load() + 1;
  retry_s_ = settings_.retry_initial_s;
  return true;
}

std::string ResultPublisher::broker() const {
  return settings_.host + ":" + std::to_string(settings_.port);
}

std::uint64_t ResultPublisher::waiting() const {
  const std::uint64_t last = store_.last_record();
  return last > acked_.load() ? last - acked_.load() : 0;
}

void ResultPublisher::run() {
  log_.info("MQTT: publishing results of station " + settings_.station + " to " + broker() +
            (settings_.ca_file.empty() ? "" : " (TLS)") + " under " + settings_.topic_prefix + "/" +
            settings_.station + "/; " + results_waiting(waiting()));
  while (true) {
    {
      std::lock_guard lock(mutex_);
      if (stop_) break;
    }
    if (!connected_) {
      if (!connect()) continue;
    }
    const int rc = mosquitto_loop(mosq_.get(), settings_.poll_interval_ms, 1);
    const int saved_errno = errno;
    if (rc != MOSQ_ERR_SUCCESS) {
      connection_lost(describe(rc, saved_errno));
      continue;
    }
    if (refused_) {
      mosquitto_disconnect(mosq_.get());
      connection_lost("the broker refused a message");
      continue;
    }
    if (session_ready_) fill_window();
    save_acked(false);
  }
  publish_offline_and_disconnect();
  save_acked(true);
}

bool ResultPublisher::connect() {
  session_ready_ = false;
  refused_ = false;
  const int rc = mosquitto_connect_bind_v5(mosq_.get(), settings_.host.c_str(), settings_.port,
                                           settings_.keepalive_s, nullptr, nullptr);
  const int saved_errno = errno;
  if (rc == MOSQ_ERR_SUCCESS) {
    connected_ = true;
    return true;
  }
  log_.warning("MQTT broker " + broker() + " unreachable: " + describe(rc, saved_errno) + "; " +
               results_waiting(waiting()) + ", retrying in " + seconds_text(retry_s_) + " s");
  wait_before_retry(retry_s_);
  return false;
}

void ResultPublisher::wait_before_retry(double seconds) {
  std::unique_lock lock(mutex_);
  wake_.wait_for(lock, std::chrono::duration<double>(seconds), [this] { return stop_; });
  retry_s_ = std::min(retry_s_ * 2.0, settings_.retry_max_s);
}

void ResultPublisher::on_connack(int reason_code) {
  if (reason_code != 0) {
    log_.error("MQTT broker " + broker() +
               " refused the connection: " + mosquitto_reason_string(reason_code) +
               " (check mqtt.username, mqtt.password_file and the broker's ACL); " +
               results_waiting(waiting()));
    refused_ = true;
    return;
  }
  session_ready_ = true;
  retry_s_ = settings_.retry_initial_s;
  in_flight_.clear();
  mid_record_.clear();
  next_record_ = acked_.load() + 1;
  const std::string online = "online";
  publish(topics_.status, online, "text/plain", true, 0, 0, nullptr);
  const std::uint64_t n = waiting();
  log_.info("MQTT broker " + broker() + " connected; " +
            (n == 0 ? std::string("no results waiting")
                    : std::to_string(n) + (n == 1 ? " result" : " results") + " to publish"));
}

void ResultPublisher::on_puback(int mid, int reason_code) {
  if (mid == offline_mid_) offline_acked_ = true;
  const auto found = mid_record_.find(mid);
  if (found == mid_record_.end()) return;  // a status message
  const std::uint64_t record = found->second;
  mid_record_.erase(found);
  if (reason_code >= 0x80) {
    log_.error("MQTT broker " + broker() + " refused record " + std::to_string(record) + ": " +
               mosquitto_reason_string(reason_code) +
               " (check the broker's ACL for the topics under " + settings_.topic_prefix + ")");
    refused_ = true;
    return;
  }
  for (InFlight& f : in_flight_) {
    if (f.record == record) --f.unacked_messages;
  }
  while (!in_flight_.empty() && in_flight_.front().unacked_messages <= 0) {
    acked_ = in_flight_.front().record;
    in_flight_.pop_front();
  }
}

void ResultPublisher::connection_lost(const std::string& reason) {
  connected_ = false;
  session_ready_ = false;
  in_flight_.clear();
  mid_record_.clear();
  next_record_ = acked_.load() + 1;
  save_acked(true);
  log_.warning("MQTT broker " + broker() + " connection lost: " + reason + "; " +
               results_waiting(waiting()) + ", retrying in " + seconds_text(retry_s_) + " s");
  wait_before_retry(retry_s_);
}

void ResultPublisher::fill_window() {
  const std::uint64_t last = store_.last_record();
  const auto window = static_cast<std::size_t>(std::max(settings_.max_records_in_flight, 1));
  while (session_ready_ && !refused_ && in_flight_.size() < window && next_record_ <= last) {
    publish_record(next_record_++);
  }
  // Records skipped as missing are done at once.
  while (!in_flight_.empty() && in_flight_.front().unacked_messages <= 0) {
    acked_ = in_flight_.front().record;
    in_flight_.pop_front();
  }
}

void ResultPublisher::publish_record(std::uint64_t record) {
  const std::string path = store_.record_path(record) + "/report.pb";
  auto bytes = analysis::read_file_bytes(path);
  v1::InspectionReport report;
  if (!bytes || !report.ParseFromString(*bytes)) {
    // Never written (a failed report write uses up its number) or deleted by retention.
    std::uint64_t oldest = 0;
    std::error_code ec;
    for (const auto& e : fs::directory_iterator(fs::path(path).parent_path().parent_path(), ec)) {
      const std::uint64_t n = record_number(e.path().filename().string());
      if (n > record && (oldest == 0 || n < oldest)) oldest = n;
    }
    const std::uint64_t resume = oldest == 0 ? store_.last_record() + 1 : oldest;
    log_.warning("MQTT: record " + std::to_string(record) +
                 (resume > record + 1 ? ".." + std::to_string(resume - 1) : "") +
                 " not in the report store (" + (bytes ? "unreadable report.pb" : bytes.message()) +
                 "; deleted by report_retention before it was published, or never written): "
                 "not published");
    in_flight_.push_back(InFlight{resume - 1, 0});
    next_record_ = resume;
    return;
  }
  const std::uint32_t seq = report.result_seq();
  const std::string json =
      result_summary_json(report, PublishedIds{settings_.station, boot_id_, record, seq});
  in_flight_.push_back(InFlight{record, 2});
  int mid = 0;
  if (publish(topics_.result, *bytes, "application/x-protobuf", false, record, seq, &mid)) {
    mid_record_[mid] = record;
  }
  if (publish(topics_.json, json, "application/json", false, record, seq, &mid)) {
    mid_record_[mid] = record;
  }
  log_.debug("MQTT: published record " + std::to_string(record) + " (seq " + std::to_string(seq) +
             ")");
}

bool ResultPublisher::publish(const std::string& topic, const std::string& payload,
                              const char* content_type, bool retain, std::uint64_t record,
                              std::uint32_t result_seq, int* mid) {
  Properties props;
  mosquitto_property_add_string(&props.list, MQTT_PROP_CONTENT_TYPE, content_type);
  props.user("station", settings_.station);
  props.user("boot_id", std::to_string(boot_id_));
  if (record != 0) {
    props.user("record", std::to_string(record));
    props.user("result_seq", std::to_string(result_seq));
  }
  const int rc =
      mosquitto_publish_v5(mosq_.get(), mid, topic.c_str(), static_cast<int>(payload.size()),
                           payload.data(), 1, retain, props.list);
  const int saved_errno = errno;
  if (rc == MOSQ_ERR_SUCCESS) return true;
  // Not sent: the connection is going down (the loop notices) or the message is too large
  // for the broker; either way the record stays unacknowledged and is sent again.
  log_.warning("MQTT: cannot publish " + topic +
               (record != 0 ? " for record " + std::to_string(record) : std::string()) + ": " +
               describe(rc, saved_errno));
  if (rc == MOSQ_ERR_OVERSIZE_PACKET || rc == MOSQ_ERR_PAYLOAD_SIZE) refused_ = true;
  return false;
}

void ResultPublisher::save_acked(bool force) {
  const std::uint64_t acked = acked_.load();
  if (acked == saved_acked_) return;
  const auto now = Steady::now();
  if (!force && !in_flight_.empty() && now - last_save_ < kSaveEvery) return;
  auto written = analysis::write_file_atomically(acked_path_, std::to_string(acked) + "\n");
  if (!written) {
    log_.warning("MQTT: cannot record the last published result: " + written.message() +
                 " (after a restart, results may be published twice)");
  }
  saved_acked_ = acked;
  last_save_ = now;
}

void ResultPublisher::publish_offline_and_disconnect() {
  if (!connected_) return;
  if (session_ready_) {
    const std::string offline = "offline";
    offline_acked_ = false;
    if (publish(topics_.status, offline, "text/plain", true, 0, 0, &offline_mid_)) {
      // Wait for its PUBACK, so that consumers see the clean stop rather than the will.
      const auto deadline = Steady::now() + kOfflineTimeout;
      while (!offline_acked_ && Steady::now() < deadline) {
        if (mosquitto_loop(mosq_.get(), 50, 1) != MOSQ_ERR_SUCCESS) break;
      }
    }
  }
  mosquitto_disconnect(mosq_.get());
  connected_ = false;
}

}  // namespace springscan::daemon
