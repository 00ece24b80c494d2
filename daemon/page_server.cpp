#include "daemon/page_server.hpp"

#include <arpa/inet.h>
#include <civetweb.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <cstring>
#include <string_view>
#include <thread>
#include <vector>

#include "analysis/io/file_io.hpp"
#include "daemon/page_html.hpp"

namespace springscan::daemon {

namespace {

// The page needs nothing from anywhere else, and this says so to the browser: a script or a
// picture from another origin is refused even if a report text tried to bring one in.
constexpr const char* kPagePolicy =
    "default-src 'none'; script-src 'unsafe-inline'; style-src 'unsafe-inline'; "
    "img-src 'self' data:; connect-src 'self'; base-uri 'none'; form-action 'none'";

// Threads for requests that end at once (the page, a report, a picture) beside the event
// streams, so a full house of pages never keeps a report link from opening.
constexpr int kQuickRequestThreads = 8;

const char* reason_phrase(int status) {
  switch (status) {
    case 200:
      return "OK";
    case 404:
      return "Not Found";
    case 405:
      return "Method Not Allowed";
    case 503:
      return "Service Unavailable";
    default:
      return "Error";
  }
}

/// A whole response; the connection closes after it (no keep-alive: one request, one thread).
int respond(mg_connection* c, int status, const char* type, std::string_view body,
            const char* extra_headers = "") {
  mg_printf(c,
            "HTTP/1.1 %d %s\r\nContent-Type: %s\r\nContent-Length: %zu\r\n"
            "Cache-Control: no-store\r\nX-Content-Type-Options: nosniff\r\n"
            "Content-Security-Policy: %s\r\nReferrer-Policy: no-referrer\r\n%s"
            "Connection: close\r\n\r\n",
            status, reason_phrase(status), type, body.size(), kPagePolicy, extra_headers);
  mg_write(c, body.data(), body.size());
  return status;
}

bool all_digits(std::string_view text) {
  for (const char ch : text)
    if (ch < '0' || ch > '9') return false;
  return !text.empty();
}

}  // namespace

std::uint64_t page_record_path(const std::string& path, bool& picture) {
  // "/reports/r" + 12 digits (ReportStore::record_path's names) + "/" + file, nothing else.
  constexpr std::string_view kPrefix = "/reports/r";
  constexpr std::size_t kDigits = 12;
  const std::string_view p(path);
  if (p.size() <= kPrefix.size() + kDigits + 1 || p.substr(0, kPrefix.size()) != kPrefix) return 0;
  const std::string_view digits = p.substr(kPrefix.size(), kDigits);
  const std::string_view file = p.substr(kPrefix.size() + kDigits);
  if (!all_digits(digits)) return 0;
  if (file == "/report.html") {
    picture = false;
  } else if (file == "/deviation.svg") {
    picture = true;
  } else {
    return 0;
  }
  return std::stoull(std::string(digits));
}

void PageServer::ContextDeleter::operator()(mg_context* context) const { mg_stop(context); }

PageServer::PageServer(const PageSettings& settings, const ReportStore& store,
                       const std::string& station_name, Log& log)
    : settings_(settings),
      store_(store),
      log_(log),
      feed_(std::make_unique<PageFeed>(settings, store, station_name, log)) {}

PageServer::~PageServer() {
  feed_->stop();  // every event stream returns from its wait
  // mg_stop joins civetweb's listener thread, which looks at its stop flag only between
  // poll()s of up to 2 s (civetweb's SOCKET_TIMEOUT_QUANTUM). Connections wake that poll, so
  // the stop takes milliseconds, and the daemon's shutdown stays well inside its bound.
  std::atomic<bool> stopped{false};
  std::thread wake([this, &stopped] {
    while (!stopped.load()) {
      const int fd = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
      sockaddr_in addr{};
      addr.sin_family = AF_INET;
      addr.sin_port = htons(static_cast<std::uint16_t>(port_));
      addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
      if (settings_.address != "0.0.0.0")
        inet_pton(AF_INET, settings_.address.c_str(), &addr.sin_addr);
      if (fd >= 0) {
        ::connect(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr);
        ::close(fd);
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
  });
  context_.reset();  // mg_stop: joins the server's threads
  stopped = true;
  wake.join();
  mg_exit_library();
}

analysis::Expected<std::unique_ptr<PageServer>> PageServer::start(const PageSettings& settings,
                                                                  const ReportStore& store,
                                                                  const std::string& station_name,
                                                                  Log& log) {
  mg_init_library(0);  // reference-counted; the destructor pairs it
  std::unique_ptr<PageServer> server(new PageServer(settings, store, station_name, log));
  const std::string ports = settings.address + ":" + std::to_string(settings.port);
  const std::string threads = std::to_string(settings.max_clients + kQuickRequestThreads);
  const std::string timeout = std::to_string(settings.write_timeout_ms);
  const std::string max_request = std::to_string(settings.max_request_bytes);
  // No document_root: civetweb serves no file by itself; every answer comes from handle().
  const char* options[] = {"listening_ports",
                           ports.c_str(),
                           "num_threads",
                           threads.c_str(),
                           "request_timeout_ms",
                           timeout.c_str(),
                           "max_request_size",
                           max_request.c_str(),
                           "enable_keep_alive",
                           "no",
                           nullptr};
  mg_callbacks callbacks{};
  callbacks.log_message = &PageServer::log_message;
  mg_init_data init{&callbacks, server.get(), options};
  char error_text[256] = "";
  unsigned error_code = 0;
  mg_error_data error{&error_code, error_text, sizeof error_text};
  server->context_.reset(mg_start2(&init, &error));
  if (!server->context_) {
    return analysis::fail(analysis::ErrorCode::kIoError,
                          "operator page: cannot serve on " + ports + ": " + error_text);
  }
  mg_set_request_handler(server->context_.get(), "/", &PageServer::handle_request, server.get());
  mg_server_port bound[4]{};
  if (mg_get_server_ports(server->context_.get(), 4, bound) > 0) server->port_ = bound[0].port;
  return server;
}

int PageServer::handle_request(mg_connection* connection, void* self) {
  return static_cast<PageServer*>(self)->handle(connection);
}

int PageServer::log_message(const mg_connection* connection, const char* message) {
  const mg_context* context = connection != nullptr ? mg_get_context(connection) : nullptr;
  auto* self = context != nullptr ? static_cast<PageServer*>(mg_get_user_data(context)) : nullptr;
  if (self != nullptr) self->log_.debug(std::string("operator page: ") + message);
  return 1;  // handled: civetweb prints nothing itself
}

int PageServer::handle(mg_connection* c) {
  ++stats_.requests;
  const mg_request_info* info = mg_get_request_info(c);
  // Read-only: GET and nothing else, so no request can ask the station for anything.
  if (info == nullptr || std::strcmp(info->request_method, "GET") != 0)
    return respond(c, 405, "text/plain", "only GET\n", "Allow: GET\r\n");
  // local_uri_raw is decoded and not cleaned: "/a/../reports/..." stays as sent and matches
  // no path below.
  const std::string path = info->local_uri_raw != nullptr ? info->local_uri_raw : "";
  if (path == "/" || path == "/index.html")
    return respond(c, 200, "text/html; charset=utf-8", operator_page_html());
  if (path == "/events") return stream_events(c);
  if (path == "/state.json") return respond(c, 200, "application/json", *feed_->current().json);
  bool picture = false;
  if (const std::uint64_t record = page_record_path(path, picture); record != 0)
    return serve_record_file(c, record, picture);
  return respond(c, 404, "text/plain", "not found\n");
}

int PageServer::serve_record_file(mg_connection* c, std::uint64_t record, bool picture) {
  if (picture) {
    const std::string svg = feed_->deviation_svg(record);
    if (svg.empty()) return respond(c, 404, "text/plain", "no deviation map for this record\n");
    return respond(c, 200, "image/svg+xml", svg);
  }
  // The path is the store's own name for the record, never text from the request.
  auto html = analysis::read_file_bytes(store_.record_path(record) + "/report.html");
  if (!html) return respond(c, 404, "text/plain", "no such report\n");
  return respond(c, 200, "text/html; charset=utf-8", *html);
}

int PageServer::stream_events(mg_connection* c) {
  if (stats_.event_clients.fetch_add(1) >= settings_.max_clients) {
    --stats_.event_clients;
    ++stats_.refused;
    return respond(c, 503, "text/plain", "too many open pages\n", "Retry-After: 5\r\n");
  }
  // retry: the browser reconnects after 2 s, never faster than the 1 s.
  mg_printf(c,
            "HTTP/1.1 200 OK\r\nContent-Type: text/event-stream\r\nCache-Control: no-store\r\n"
            "X-Content-Type-Options: nosniff\r\nConnection: close\r\n\r\nretry: 2000\n\n");
  const auto keepalive = std::chrono::seconds(settings_.keepalive_s);
  std::uint64_t seen = 0;
  std::string chunk;
  while (!feed_->stopped()) {
    const PageFeed::Snapshot snapshot = feed_->wait_newer(seen, keepalive);
    if (feed_->stopped()) break;
    if (snapshot.version > seen) {
      chunk = "id: " + std::to_string(snapshot.version) + "\nevent: station\ndata: ";
      chunk += *snapshot.json;
      chunk += "\n\n";
      seen = snapshot.version;
    } else {
      chunk = ": keepalive\n\n";  // also finds a page that went away
    }
    // civetweb gives up a write after request_timeout_ms (write_timeout_ms): a page that does
    // not read is dropped here and its thread freed.
    if (mg_write(c, chunk.data(), chunk.size()) != static_cast<int>(chunk.size())) {
      ++stats_.dropped;
      break;
    }
  }
  --stats_.event_clients;
  return 200;
}

}  // namespace springscan::daemon
