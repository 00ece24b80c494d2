#pragma once
// The operator page's HTTP server (DESIGN.md "The operator's page"; docs/operator-page.md):
// civetweb (Debian 12 libcivetweb-dev) on its own threads, read-only, serving exactly
//   GET /                                 the page (page_html.cpp), self-contained
//   GET /events                           server-sent events: the feed's snapshot on every change
//   GET /state.json                       the current snapshot, once
//   GET /reports/r<12 digits>/report.html a record's report, from the report store
//   GET /reports/r<12 digits>/deviation.svg  its deviation colour map (from that report.html)
// and 404 for any other path (the path is matched whole, so "..", encoded or not, never
// reaches a file), 405 for any other method, 413 for a request larger than max_request_bytes.
//
// Nothing here touches the station: the station's event loop only hands its status to the
// feed (page_feed.hpp). A page that stops reading holds one server thread until its write
// times out (write_timeout_ms), and is then dropped; other pages and the station go on.

#include <atomic>
#include <cstdint>
#include <memory>
#include <string>

#include "analysis/core/expected.hpp"
#include "daemon/log.hpp"
#include "daemon/page_feed.hpp"
#include "daemon/report_store.hpp"

struct mg_connection;
struct mg_context;

namespace springscan::daemon {

/// Counters for the log and the tests. Thread-safe.
struct PageServerStats {
  std::atomic<int> event_clients{0};       ///< event streams open now
  std::atomic<std::uint64_t> dropped{0};   ///< event streams ended by a failed write
  std::atomic<std::uint64_t> refused{0};   ///< event streams refused (max_clients)
  std::atomic<std::uint64_t> requests{0};  ///< requests answered by a handler
};

class PageServer {
 public:
  /// Starts the feed over `store` and the server on settings.address:settings.port. Errors:
  /// the port cannot be bound (the message is civetweb's). `store` and `log` must outlive it.
  static analysis::Expected<std::unique_ptr<PageServer>> start(const PageSettings& settings,
                                                               const ReportStore& store,
                                                               const std::string& station_name,
                                                               Log& log);
  /// Stops the feed (ending every event stream) and the server, joining their threads.
  ~PageServer();
  PageServer(const PageServer&) = delete;
  PageServer& operator=(const PageServer&) = delete;

  /// The port actually bound.
  int port() const { return port_; }
  /// The feed, for the station's status (Station::watch_status).
  PageFeed& feed() { return *feed_; }
  const PageServerStats& stats() const { return stats_; }

 private:
  struct ContextDeleter {
    void operator()(mg_context* context) const;
  };
  PageServer(const PageSettings& settings, const ReportStore& store,
             const std::string& station_name, Log& log);
  static int handle_request(mg_connection* connection, void* self);
  static int log_message(const mg_connection* connection, const char* message);
  int handle(mg_connection* connection);
  int stream_events(mg_connection* connection);
  int serve_record_file(mg_connection* connection, std::uint64_t record, bool picture);

  PageSettings settings_;
  const ReportStore& store_;
  Log& log_;
  std::unique_ptr<PageFeed> feed_;
  std::unique_ptr<mg_context, ContextDeleter> context_;
  int port_ = 0;
  PageServerStats stats_;
};

/// The record number of "/reports/r000000000042/report.html" (picture = false) or
/// ".../deviation.svg" (picture = true); 0 for any other path.
std::uint64_t page_record_path(const std::string& path, bool& picture);

}  // namespace springscan::daemon
