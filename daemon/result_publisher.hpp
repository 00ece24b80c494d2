#pragma once
// The result publisher: every result the report store persisted goes to an MQTT broker
// (DESIGN.md "Plant integration"; topics and payloads in docs/plant-integration.md).
//
// The report store is the queue. The publisher runs on its own thread, looks at the store's
// newest record and publishes, in record order, every record after the last one the broker
// acknowledged (PUBACK, QoS 1). That record number is kept in <report_dir>/mqtt_acked_record
// (written atomically), so a broker outage or a daemon restart delays publishing but loses
// nothing: on start and on every reconnect, everything after it is published again. Nothing
// here is ever called by the event loop or the job runner, so a slow or absent broker can
// neither block the PLC handshake nor the analysis.
//
// Each record is two messages: <prefix>/<station>/result (the InspectionReport protobuf) and
// <prefix>/<station>/result/json (result_summary.hpp). Both carry MQTT v5 user properties
// boot_id, record, result_seq and station (the JSON also in its body), so consumers drop the
// duplicates that at-least-once delivery allows. <prefix>/<station>/status is retained:
// "online" after connecting, "offline" on a clean stop and as the last will.

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

#include "analysis/core/expected.hpp"
#include "daemon/log.hpp"
#include "daemon/report_store.hpp"

struct mosquitto;

namespace springscan::daemon {

struct MqttSettings {
  bool enabled = false;                        ///< off unless the config has an mqtt { } section
  std::string host = "127.0.0.1";              ///< broker host name or address
  int port = 1883;                             ///< 1883 plain, 8883 usual with TLS
  std::string client_id;                       ///< empty: "springscand-<station>"
  std::string topic_prefix = "springscan/v1";  ///< topics are <topic_prefix>/<station>/...
  std::string station;                         ///< topic station name; empty: the station_name
  std::string ca_file;            ///< TLS is on when set: the CA of the broker's certificate
  std::string cert_file;          ///< TLS client certificate (with key_file); empty: none
  std::string key_file;           ///< TLS client key
  std::string username;           ///< empty: anonymous
  std::string password_file;      ///< the password (first line of the file); empty: none
  int keepalive_s = 30;           ///< MQTT keep-alive; a dead broker is noticed within 1.5x this
  double retry_initial_s = 2.0;   ///< wait after the first failed connection attempt
  double retry_max_s = 30.0;      ///< the wait doubles after each failure up to this
  int max_records_in_flight = 8;  ///< records published and not yet acknowledged
  int poll_interval_ms = 20;      ///< how often the store is looked at while connected
};

/// mosquitto_lib_init() for the life of the object: one in main() (and one per test).
class MosquittoLibrary {
 public:
  MosquittoLibrary();
  ~MosquittoLibrary();
  MosquittoLibrary(const MosquittoLibrary&) = delete;
  MosquittoLibrary& operator=(const MosquittoLibrary&) = delete;
};

/// The topics of `station` under `settings.topic_prefix`.
struct MqttTopics {
  std::string result;  ///< <prefix>/<station>/result
  std::string json;    ///< <prefix>/<station>/result/json
  std::string status;  ///< <prefix>/<station>/status
};
MqttTopics mqtt_topics(const MqttSettings& settings);

class ResultPublisher {
 public:
  /// Starts publishing the records of `store` (which must outlive the publisher); `boot_id`
  /// is the station's BOOT_ID. Fails only on settings libmosquitto refuses (TLS files); an
  /// unreachable broker is retried on the publisher's thread. settings.station must be set.
  static analysis::Expected<std::unique_ptr<ResultPublisher>> start(const MqttSettings& settings,
                                                                    const ReportStore& store,
                                                                    std::uint16_t boot_id,
                                                                    Log& log);
  /// Publishes "offline" (retained) when connected, writes the acknowledged record, joins.
  ~ResultPublisher();
  ResultPublisher(const ResultPublisher&) = delete;
  ResultPublisher& operator=(const ResultPublisher&) = delete;

  /// The newest record the broker acknowledged (as in mqtt_acked_record).
  std::uint64_t acked_record() const { return acked_.load(); }

 private:
  struct MosquittoDeleter {
    void operator()(mosquitto* m) const;
  };
  struct InFlight {
    std::uint64_t record = 0;
    int unacked_messages = 0;
  };

  ResultPublisher(const MqttSettings& settings, const ReportStore& store, std::uint16_t boot_id,
                  Log& log);
  analysis::Expected<bool> configure();
  void run();
  bool connect();
  void on_connack(int reason_code);
  void on_puback(int mid, int reason_code);
  void connection_lost(const std::string& reason);
  void fill_window();
  void publish_record(std::uint64_t record);
  bool publish(const std::string& topic, const std::string& payload, const char* content_type,
               bool retain, std::uint64_t record, std::uint32_t result_seq, int* mid);
  void save_acked(bool force);
  void publish_offline_and_disconnect();
  void wait_before_retry(double seconds);
  std::uint64_t waiting() const;
  std::string broker() const;

  MqttSettings settings_;
  MqttTopics topics_;
  const ReportStore& store_;
  std::uint16_t boot_id_;
  Log& log_;
  std::string acked_path_;
  std::unique_ptr<mosquitto, MosquittoDeleter> mosq_;

  // Publisher thread only.
  bool connected_ = false;      // TCP (and TLS) up, CONNACK may be pending
  bool session_ready_ = false;  // CONNACK accepted
  bool refused_ = false;        // the broker refused a message or the connection
  std::uint64_t next_record_ = 1;
  std::deque<InFlight> in_flight_;
  std::map<int, std::uint64_t> mid_record_;
  std::uint64_t saved_acked_ = 0;
  std::chrono::steady_clock::time_point last_save_;
  double retry_s_ = 0;
  int offline_mid_ = -1;
  bool offline_acked_ = false;

  std::atomic<std::uint64_t> acked_{0};
  std::mutex mutex_;
  std::condition_variable wake_;
  bool stop_ = false;
  std::thread thread_;
};

}  // namespace springscan::daemon
