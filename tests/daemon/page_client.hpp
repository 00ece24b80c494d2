#pragma once
// Plain-socket HTTP clients for the operator page tests: one request and its whole answer
// (the server closes every connection), an event stream read line by line, and a client that
// opens the event stream and never reads. Raw bytes on purpose: the tests send requests no
// browser would (huge headers, "..", bad methods).

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <sys/time.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <string>

namespace springscan::daemon::testing {

/// A connected loopback socket (-1 on failure); `receive_buffer` > 0 shrinks SO_RCVBUF first.
inline int connect_loopback(int port, int receive_buffer = 0, double timeout_s = 10.0) {
  const int fd = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
  if (fd < 0) return -1;
  if (receive_buffer > 0)
    ::setsockopt(fd, SOL_SOCKET, SO_RCVBUF, &receive_buffer, sizeof receive_buffer);
  timeval tv{static_cast<time_t>(timeout_s),
             static_cast<suseconds_t>((timeout_s - static_cast<int>(timeout_s)) * 1e6)};
  ::setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
  ::setsockopt(fd, SOL_SOCKET, SO_SNDTIMEO, &tv, sizeof tv);
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_port = htons(static_cast<std::uint16_t>(port));
  addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  if (::connect(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr) != 0) {
    ::close(fd);
    return -1;
  }
  return fd;
}

inline bool send_all(int fd, const std::string& bytes) {
  std::size_t sent = 0;
  while (sent < bytes.size()) {
    const ssize_t n = ::send(fd, bytes.data() + sent, bytes.size() - sent, MSG_NOSIGNAL);
    if (n <= 0) return false;
    sent += static_cast<std::size_t>(n);
  }
  return true;
}

struct HttpAnswer {
  int status = 0;  ///< 0: no status line came back
  std::string head;
  std::string body;
};

/// Sends `request` as is and reads until the server closes the connection.
inline HttpAnswer raw_request(int port, const std::string& request) {
  HttpAnswer answer;
  const int fd = connect_loopback(port);
  if (fd < 0) return answer;
  send_all(fd, request);  // the server may answer (and close) before reading all of it
  std::string all;
  char buffer[65536];
  for (;;) {
    const ssize_t n = ::recv(fd, buffer, sizeof buffer, 0);
    if (n <= 0) break;
    all.append(buffer, static_cast<std::size_t>(n));
  }
  ::close(fd);
  const std::size_t end = all.find("\r\n\r\n");
  answer.head = all.substr(0, end);
  if (end != std::string::npos) answer.body = all.substr(end + 4);
  if (all.rfind("HTTP/1.", 0) == 0 && all.size() > 12) answer.status = std::atoi(all.c_str() + 9);
  return answer;
}

inline HttpAnswer http_get(int port, const std::string& target) {
  return raw_request(port, "GET " + target + " HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n");
}

/// An open event stream: next_data() returns the next event's data line.
class EventStream {
 public:
  explicit EventStream(int port, double timeout_s = 10.0)
      : fd_(connect_loopback(port, 0, timeout_s)) {
    if (fd_ >= 0) send_all(fd_, "GET /events HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n");
  }
  ~EventStream() {
    if (fd_ >= 0) ::close(fd_);
  }
  EventStream(const EventStream&) = delete;
  EventStream& operator=(const EventStream&) = delete;
  bool ok() const { return fd_ >= 0; }
  /// Ends a next_data() blocked on another thread (it returns "").
  void shutdown() {
    if (fd_ >= 0) ::shutdown(fd_, SHUT_RDWR);
  }

  /// The data of the next "event: station"; empty on timeout or a closed stream.
  std::string next_data() {
    for (;;) {
      const std::size_t at = buffer_.find("\ndata: ");
      if (at != std::string::npos) {
        const std::size_t end = buffer_.find('\n', at + 7);
        if (end != std::string::npos) {
          std::string data = buffer_.substr(at + 7, end - at - 7);
          buffer_.erase(0, end);
          return data;
        }
      }
      char chunk[65536];
      const ssize_t n = ::recv(fd_, chunk, sizeof chunk, 0);
      if (n <= 0) return "";
      buffer_.append(chunk, static_cast<std::size_t>(n));
    }
  }

 private:
  int fd_ = -1;
  std::string buffer_;
};

}  // namespace springscan::daemon::testing
