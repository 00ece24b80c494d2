#include "daemon/modbus_server.hpp"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <sys/select.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>

namespace springscan::daemon {

namespace {

constexpr int kMaxFramesPerWakeup = 16;  // fairness: then the next client gets its turn
constexpr int kPartialRecheckMs = 5;     // a client with a partial frame is re-peeked this often
constexpr unsigned kTcpUserTimeoutMs = 10000;

std::string errno_text(int error) { return std::strerror(error); }

std::string peer_name(const sockaddr_in& addr) {
  char text[INET_ADDRSTRLEN] = {};
  inet_ntop(AF_INET, &addr.sin_addr, text, sizeof text);
  return std::string(text) + ":" + std::to_string(ntohs(addr.sin_port));
}

bool is_write(int function) {
  return function == MODBUS_FC_WRITE_SINGLE_COIL || function == MODBUS_FC_WRITE_SINGLE_REGISTER ||
         function == MODBUS_FC_WRITE_MULTIPLE_COILS ||
         function == MODBUS_FC_WRITE_MULTIPLE_REGISTERS;
}

void set_client_options(int fd) {
  const int one = 1;
  setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
  setsockopt(fd, SOL_SOCKET, SO_KEEPALIVE, &one, sizeof one);
  // A PLC that vanishes (cable pulled) is noticed even while we have unsent replies.
  const unsigned user_timeout = kTcpUserTimeoutMs;
  setsockopt(fd, IPPROTO_TCP, TCP_USER_TIMEOUT, &user_timeout, sizeof user_timeout);
}

int ms_until(ModbusServer::Clock::time_point now, ModbusServer::Clock::time_point deadline) {
  const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - now).count();
  return static_cast<int>(std::clamp<long long>(left + 1, 0, 1 << 30));
}

}  // namespace

ModbusServer::ModbusServer(ModbusServerSettings settings, modbus_mapping_t* mapping, Log& log)
    : settings_(std::move(settings)), mapping_(mapping), log_(log) {}

ModbusServer::~ModbusServer() {
  for (const Client& c : clients_) close(c.fd);
  if (listen_fd_ >= 0) close(listen_fd_);
}

analysis::Expected<std::unique_ptr<ModbusServer>> ModbusServer::open(
    const ModbusServerSettings& settings, modbus_mapping_t* mapping, Log& log) {
  using analysis::fail;
  std::unique_ptr<ModbusServer> server(new ModbusServer(settings, mapping, log));
  for (const std::string& text : settings.allowed_clients) {
    in_addr addr{};
    if (inet_pton(AF_INET, text.c_str(), &addr) != 1) {
      return fail("modbus.allowed_clients: '" + text + "' is not an IPv4 address");
    }
    server->allowed_.push_back(addr.s_addr);
  }
  for (const std::string& text : settings.plc_clients) {
    in_addr addr{};
    if (inet_pton(AF_INET, text.c_str(), &addr) != 1) {
      return fail("modbus.plc_clients: '" + text + "' is not an IPv4 address");
    }
    server->plc_.push_back(addr.s_addr);
  }
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_port = htons(static_cast<std::uint16_t>(settings.port));
  if (inet_pton(AF_INET, settings.bind_address.c_str(), &addr.sin_addr) != 1) {
    return fail("modbus.bind_address: '" + settings.bind_address + "' is not an IPv4 address");
  }
  const std::string where = settings.bind_address + ":" + std::to_string(settings.port);
  server->listen_fd_ = socket(AF_INET, SOCK_STREAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  if (server->listen_fd_ < 0) return fail("Modbus socket: " + errno_text(errno));
  const int one = 1;
  setsockopt(server->listen_fd_, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
  if (bind(server->listen_fd_, reinterpret_cast<sockaddr*>(&addr), sizeof addr) != 0) {
    const int error = errno;
    return fail("cannot listen for Modbus on " + where + ": " + errno_text(error) +
                (error == EACCES ? " (port < 1024 needs CAP_NET_BIND_SERVICE)" : "") +
                (error == EADDRINUSE ? " (another process holds the port)" : ""));
  }
  // A backlog that holds a burst of reconnects (a PLC and its stale sessions) without SYN drops.
  if (listen(server->listen_fd_, 64) != 0)
    return fail("listen " + where + ": " + errno_text(errno));
  socklen_t length = sizeof addr;
  getsockname(server->listen_fd_, reinterpret_cast<sockaddr*>(&addr), &length);
  server->port_ = ntohs(addr.sin_port);
  // The context only frames and answers requests on sockets we accepted; it never connects.
  server->ctx_.reset(modbus_new_tcp(settings.bind_address.c_str(), server->port_));
  if (!server->ctx_) return fail("modbus_new_tcp: " + std::string(modbus_strerror(errno)));
  modbus_set_error_recovery(server->ctx_.get(), MODBUS_ERROR_RECOVERY_NONE);
  modbus_set_slave(server->ctx_.get(), settings.unit_id);
  // The whole frame is already in the socket buffer when libmodbus reads; these only bound a
  // bug (libmodbus waits forever for an indication by default, #95/#173/#215).
  modbus_set_indication_timeout(server->ctx_.get(), 0, 100000);
  modbus_set_byte_timeout(server->ctx_.get(), 0, 100000);
  return server;
}

bool ModbusServer::allowed(std::uint32_t address_be) const {
  return allowed_.empty() ||
         std::find(allowed_.begin(), allowed_.end(), address_be) != allowed_.end();
}

bool ModbusServer::is_plc(std::uint32_t address_be) const {
  return plc_.empty() || std::find(plc_.begin(), plc_.end(), address_be) != plc_.end();
}

std::ptrdiff_t ModbusServer::slot_for(std::uint32_t address_be) const {
  // Least recently active first: a PLC polls every few hundred ms, so a connection it still
  // uses is never the stalest; half-open ones (cable pulled, PLC rebooted) are.
  const auto stalest = [this](const auto& candidate) {
    std::ptrdiff_t best = -1;
    for (std::size_t i = 0; i < clients_.size(); ++i) {
      if (!candidate(clients_[i])) continue;
      if (best < 0 ||
          clients_[i].last_activity < clients_[static_cast<std::size_t>(best)].last_activity)
        best = static_cast<std::ptrdiff_t>(i);
    }
    return best;
  };
  const auto same_address = [address_be](const Client& c) { return c.address_be == address_be; };
  const auto per_address =
      static_cast<std::ptrdiff_t>(std::count_if(clients_.begin(), clients_.end(), same_address));
  if (settings_.max_connections_per_address > 0 &&
      per_address >= settings_.max_connections_per_address)
    return stalest(same_address);
  if (clients_.size() < static_cast<std::size_t>(settings_.max_connections)) return -1;
  const std::ptrdiff_t other = stalest([this](const Client& c) { return !is_plc(c.address_be); });
  if (other >= 0) return other;
  // Only PLC connections are left: a PLC newcomer replaces the stalest (its own dead session).
  return is_plc(address_be) ? stalest([](const Client&) { return true; }) : -2;
}

void ModbusServer::add_poll_fds(std::vector<pollfd>& fds) const {
  fds.push_back(pollfd{listen_fd_, POLLIN, 0});
  for (const Client& c : clients_) {
    // A partial frame stays in the buffer (we only peek), so polling it for POLLIN would spin:
    // it is re-peeked on the short timer of expire() instead.
    fds.push_back(pollfd{c.fd, static_cast<short>(c.partial ? 0 : POLLIN), 0});
  }
}

void ModbusServer::service(const std::vector<pollfd>& fds, Clock::time_point now,
                           const WriteHook& on_write) {
  const auto revents_of = [&fds](int fd) -> short {
    for (const pollfd& p : fds) {
      if (p.fd == fd) return p.revents;
    }
    return 0;
  };
  for (std::size_t i = clients_.size(); i-- > 0;) {
    Client& c = clients_[i];
    const short ev = revents_of(c.fd);
    if ((ev & (POLLIN | POLLHUP | POLLERR)) == 0 && !c.partial) continue;
    if (!serve_client(c, now, on_write)) close_client(i, "");
  }
  if ((revents_of(listen_fd_) & POLLIN) != 0) accept_clients(now);
}

void ModbusServer::accept_clients(Clock::time_point now) {
  for (;;) {
    sockaddr_in addr{};
    socklen_t length = sizeof addr;
    const int fd = accept4(listen_fd_, reinterpret_cast<sockaddr*>(&addr), &length,
                           SOCK_NONBLOCK | SOCK_CLOEXEC);
    if (fd < 0) {
      if (errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR && errno != ECONNABORTED) {
        log_.warning("Modbus accept failed: " + errno_text(errno) +
                     " (file descriptors exhausted? check LimitNOFILE)");
      }
      return;
    }
    const std::string peer = peer_name(addr);
    if (!allowed(addr.sin_addr.s_addr)) {
      ++stats_.refused_not_allowed;
      log_.warning("refused Modbus connection from " + peer +
                   ": not in modbus.allowed_clients of the config. If this is the PLC, add its "
                   "address there and restart springscand.");
      close(fd);
      continue;
    }
    // libmodbus select()s on the fd: fds >= FD_SETSIZE overflowed before 3.1.12 (notes sec. 2).
    const std::ptrdiff_t victim = fd < FD_SETSIZE ? slot_for(addr.sin_addr.s_addr) : -2;
    if (victim == -2) {
      ++stats_.refused_too_many;
      log_.warning("refused Modbus connection from " + peer + ": all " +
                   std::to_string(clients_.size()) +
                   " slots (modbus.max_connections) are held by PLC addresses "
                   "(modbus.plc_clients) and this is not one of them");
      close(fd);
      continue;
    }
    if (victim >= 0) {
      ++stats_.evicted;
      const Client& old = clients_[static_cast<std::size_t>(victim)];
      const auto idle_s =
          std::chrono::duration_cast<std::chrono::milliseconds>(now - old.last_activity).count() /
          1000.0;
      close_client(static_cast<std::size_t>(victim),
                   "dropped for the new connection from " + peer + " (least recently active, " +
                       std::to_string(idle_s) + " s idle; modbus.max_connections = " +
                       std::to_string(settings_.max_connections) + ")");
    }
    set_client_options(fd);
    ++stats_.accepted;
    clients_.push_back(Client{fd, peer, addr.sin_addr.s_addr, now, false, now});
    log_.info("Modbus client " + peer + " connected (" + std::to_string(clients_.size()) +
              " of at most " + std::to_string(settings_.max_connections) + ")");
  }
}

bool ModbusServer::serve_client(Client& client, Clock::time_point now, const WriteHook& on_write) {
  std::uint8_t peek[kMaxAduBytes];
  for (int frames = 0; frames < kMaxFramesPerWakeup; ++frames) {
    const ssize_t n = recv(client.fd, peek, sizeof peek, MSG_PEEK | MSG_DONTWAIT);
    if (n == 0) return false;  // orderly close by the client
    if (n < 0) return errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR;
    const auto size = static_cast<std::size_t>(n);
    client.last_activity = now;
    FrameHeader header;
    if (size >= kMbapLengthPrefix) {
      header = check_mbap_prefix(peek, size);
      if (!header.valid) {
        ++stats_.closed_bad_frame;
        log_.warning("closing Modbus client " + client.peer + ": not a Modbus TCP frame (" +
                     header.problem + ")");
        return false;
      }
    }
    if (size < kMbapLengthPrefix || size < header.frame_bytes) {
      if (!client.partial) client.partial_since = now;
      client.partial = true;
      return true;
    }
    client.partial = false;
    if (!serve_frame(client, header.frame_bytes, on_write)) return false;
  }
  return true;
}

bool ModbusServer::serve_frame(Client& client, std::size_t frame_bytes, const WriteHook& on_write) {
  std::uint8_t req[MODBUS_TCP_MAX_ADU_LENGTH];
  ++stats_.requests;
  modbus_t* ctx = ctx_.get();
  modbus_set_socket(ctx, client.fd);
  // Validate on a peeked copy first: libmodbus 3.1.6 trusts lengths it should not.
  const ssize_t n = recv(client.fd, req, frame_bytes, MSG_PEEK | MSG_DONTWAIT);
  if (n != static_cast<ssize_t>(frame_bytes)) return false;
  const RequestVerdict verdict =
      check_request(req, frame_bytes, RequestCheckSettings{settings_.unit_id});
  if (verdict.exception != 0) {
    ++stats_.exceptions;
    log_.debug("Modbus client " + client.peer + ": exception " + std::to_string(verdict.exception) +
               ": " + verdict.problem);
    if (recv(client.fd, req, frame_bytes, MSG_DONTWAIT) != static_cast<ssize_t>(frame_bytes)) {
      return false;
    }
    if (req[kMbapHeaderBytes] >= 0x80) {
      return reply_high_function_exception(client, req, static_cast<unsigned>(verdict.exception));
    }
    return modbus_reply_exception(ctx, req, static_cast<unsigned>(verdict.exception)) >= 0;
  }
  const int received = modbus_receive(ctx, req);
  if (received != static_cast<int>(frame_bytes)) {
    log_.warning("closing Modbus client " + client.peer + ": libmodbus read " +
                 std::to_string(received) + " bytes of a " + std::to_string(frame_bytes) +
                 "-byte frame (" + modbus_strerror(errno) + ")");
    return false;
  }
  if (modbus_reply(ctx, req, received, mapping_) < 0) {
    // A client that does not read its replies fills the socket buffer: drop it, never block.
    log_.warning("closing Modbus client " + client.peer +
                 ": reply failed: " + modbus_strerror(errno));
    return false;
  }
  if (is_write(req[kMbapHeaderBytes]) && on_write) on_write();
  return true;
}

bool ModbusServer::reply_high_function_exception(const Client& client, const std::uint8_t* req,
                                                 unsigned exception) {
  // MBAP (transaction id echoed, protocol 0, length 3, unit echoed), then the function code
  // as received (its high bit is already set) and the exception code (spec section 7).
  const std::uint8_t reply[] = {req[0],
                                req[1],
                                0,
                                0,
                                0,
                                3,
                                req[6],
                                req[kMbapHeaderBytes],
                                static_cast<std::uint8_t>(exception)};
  return send(client.fd, reply, sizeof reply, MSG_NOSIGNAL | MSG_DONTWAIT) ==
         static_cast<ssize_t>(sizeof reply);
}

int ModbusServer::expire(Clock::time_point now, int cap_ms) {
  int timeout = cap_ms;
  const auto partial_limit = std::chrono::duration_cast<Clock::duration>(
      std::chrono::duration<double>(settings_.partial_frame_timeout_s));
  const auto idle_limit = std::chrono::duration_cast<Clock::duration>(
      std::chrono::duration<double>(settings_.idle_timeout_s));
  for (std::size_t i = clients_.size(); i-- > 0;) {
    const Client& c = clients_[i];
    if (c.partial && now - c.partial_since > partial_limit) {
      ++stats_.closed_timeout;
      close_client(i, "an incomplete request stalled for more than " +
                          std::to_string(settings_.partial_frame_timeout_s) + " s");
      continue;
    }
    if (now - c.last_activity > idle_limit) {
      ++stats_.closed_timeout;
      close_client(i, "idle for more than " + std::to_string(settings_.idle_timeout_s) + " s");
      continue;
    }
    timeout = std::min(timeout, ms_until(now, c.last_activity + idle_limit));
    if (c.partial) timeout = std::min(timeout, kPartialRecheckMs);
  }
  return timeout;
}

void ModbusServer::close_client(std::size_t index, const std::string& why) {
  const Client c = clients_[index];
  close(c.fd);
  clients_.erase(clients_.begin() + static_cast<std::ptrdiff_t>(index));
  if (why.empty()) {
    log_.info("Modbus client " + c.peer + " disconnected");
  } else {
    log_.warning("closed Modbus client " + c.peer + ": " + why);
  }
}

}  // namespace springscan::daemon
