#pragma once
// The operator page's data (DESIGN.md "The operator's page"; docs/operator-page.md): the
// station's state as the state machine publishes it, the last results as the report store
// holds them, and the shift's counts, kept as one JSON snapshot that the page's event stream
// sends whole.
//
// Nothing here can slow the inspection. The event loop only hands over the machine status
// (on_status: a lock, a compare, a copy). The feed's own thread watches the report store, as
// the MQTT publisher does (the store is the queue), reads each new record's report.pb and
// rebuilds the snapshot. Readers (one thread per page, page_server.cpp) wait for a newer
// snapshot and take a shared pointer to it: the "queue" of each client is one version number,
// so a slow client skips intermediate states but never a result (every snapshot carries the
// last results), and holds no memory beyond the snapshot it is writing.

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <ctime>
#include <deque>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "daemon/log.hpp"
#include "daemon/page_text.hpp"
#include "daemon/report_store.hpp"
#include "daemon/state_machine.hpp"
#include "proto/springscan.pb.h"

namespace springscan::daemon {

struct PageSettings {
  bool enabled = false;               ///< off unless the config has an http { } section
  std::string address = "127.0.0.1";  ///< IPv4 address the page is served on
  int port = 8080;                    ///< TCP port; 0 takes a free one (tests), sent to systemd
                                      ///< as HTTP_PORT= and logged
  int max_clients = 64;               ///< open pages (event streams) at once; more get 503
  int write_timeout_ms = 2000;        ///< a client that does not take an update this long is
                                      ///< dropped (its page reconnects by itself)
  int max_request_bytes = 8192;       ///< request line and headers; larger requests get 413
  int recent_results = 50;            ///< rows of the page's results table
  int keepalive_s = 15;               ///< a comment line on an idle event stream this often
  int watch_interval_ms = 50;         ///< how often the feed looks at the report store
  std::vector<int> shift_starts_min = {360, 840, 1320};  ///< local time of day (minutes after
                                                         ///< midnight) each shift starts
};

class PageFeed {
 public:
  /// A snapshot and its version (1, 2, ...; 0: none yet).
  struct Snapshot {
    std::uint64_t version = 0;
    std::shared_ptr<const std::string> json;
  };

  /// Loads the last results and the shift's counts from `store` and starts watching it.
  /// `store` and `log` must outlive the feed.
  PageFeed(const PageSettings& settings, const ReportStore& store, std::string station_name,
           Log& log);
  /// Stops the watcher and wakes every waiting reader.
  ~PageFeed();
  PageFeed(const PageFeed&) = delete;
  PageFeed& operator=(const PageFeed&) = delete;

  /// Called by the event loop after every update. Never blocks on I/O.
  void on_status(const MachineStatus& status, bool calibration_drift = false);
  /// The current snapshot.
  Snapshot current() const;
  /// Waits until a snapshot newer than `seen` exists, `timeout` passed or stop() was called;
  /// returns the current one. Thread-safe.
  Snapshot wait_newer(std::uint64_t seen, std::chrono::milliseconds timeout) const;
  /// Wakes every reader for good (the server is stopping).
  void stop();
  bool stopped() const;
  /// The deviation picture of `record` (cached for the newest record); empty when none.
  std::string deviation_svg(std::uint64_t record) const;

 private:
  void watch();
  void load_history();
  bool take_new_records();
  void add_result(PageResult result);
  void cache_picture(std::uint64_t record);
  void rebuild();

  PageSettings settings_;
  const ReportStore& store_;
  std::string station_name_;
  Log& log_;

  // Watcher thread only.
  std::uint64_t last_record_ = 0;
  std::deque<PageResult> recent_;  // newest first
  std::time_t shift_start_ = 0;
  ShiftCounts shift_;

  mutable std::mutex mutex_;
  mutable std::condition_variable changed_;  // a new snapshot, or stop
  std::condition_variable wake_watcher_;     // a new status, or stop
  PageStatus status_;
  bool status_dirty_ = false;
  bool stop_ = false;
  Snapshot snapshot_;
  std::uint64_t svg_record_ = 0;
  std::string svg_;
  std::thread thread_;
};

}  // namespace springscan::daemon
