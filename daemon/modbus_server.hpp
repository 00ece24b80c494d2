#pragma once
// The Modbus TCP server on libmodbus (notes section 2). We accept connections ourselves and
// check the allow-list there; each client socket is non-blocking and polled by the caller's
// event loop. A request reaches libmodbus only when its whole MBAP frame has arrived (peeked
// with MSG_PEEK) and passed check_request(); a frame that does not complete within the
// partial-frame timeout, or a connection idle past the idle timeout, is closed, so a slow
// client never holds up the others. The server never uses MODBUS_ERROR_RECOVERY_LINK.
//
// Thread safety: none; one thread (the event loop) calls everything, and that thread also owns
// the register image, so every reply sees one consistent state.

#include <modbus/modbus.h>
#include <poll.h>

#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "analysis/core/expected.hpp"
#include "daemon/log.hpp"
#include "daemon/request_check.hpp"

namespace springscan::daemon {

struct ModbusServerSettings {
  std::string bind_address = "0.0.0.0";      ///< IPv4 address to listen on
  int port = 502;                            ///< 0: any free port (tests)
  std::vector<std::string> allowed_clients;  ///< IPv4 addresses; empty allows any
  std::uint8_t unit_id = 1;                  ///< also answered: 0xFF
  /// The PLC's address(es), IPv4: a PLC newcomer always gets a slot, taken from a non-PLC
  /// connection first. Empty: every allowed address counts as a PLC address.
  std::vector<std::string> plc_clients;
  int max_connections = 4;  ///< when full, the least recently active connection makes room
  int max_connections_per_address = 0;   ///< 0: no limit below max_connections
  double idle_timeout_s = 60.0;          ///< a connection silent this long is closed
  double partial_frame_timeout_s = 0.5;  ///< a started frame must complete within this
};

/// Counters for the log, tests and the soak figures.
struct ModbusServerStats {
  std::uint64_t accepted = 0;
  std::uint64_t refused_not_allowed = 0;
  std::uint64_t refused_too_many = 0;  ///< full of PLC connections, newcomer not a PLC
  std::uint64_t evicted = 0;           ///< connections dropped to make room for a newcomer
  std::uint64_t requests = 0;
  std::uint64_t exceptions = 0;
  std::uint64_t closed_bad_frame = 0;
  std::uint64_t closed_timeout = 0;
};

class ModbusServer {
 public:
  using Clock = std::chrono::steady_clock;
  /// Called after a request that wrote coils or holding registers was answered.
  using WriteHook = std::function<void()>;

  /// Binds and listens. `mapping` and `log` are not owned and must outlive the server.
  static analysis::Expected<std::unique_ptr<ModbusServer>> open(
      const ModbusServerSettings& settings, modbus_mapping_t* mapping, Log& log);
  ~ModbusServer();
  ModbusServer(const ModbusServer&) = delete;
  ModbusServer& operator=(const ModbusServer&) = delete;

  /// The port actually bound (useful with port 0).
  int port() const { return port_; }
  /// Appends the listening socket and every client to `fds` (POLLIN each).
  void add_poll_fds(std::vector<pollfd>& fds) const;
  /// Serves every fd in `fds` that the poll marked; others are ignored. `on_write` runs after
  /// each answered write so the caller can update its state before the next request.
  void service(const std::vector<pollfd>& fds, Clock::time_point now, const WriteHook& on_write);
  /// Closes idle connections and stalled partial frames. Returns the poll timeout (ms) until
  /// the next deadline, capped at `cap_ms`.
  int expire(Clock::time_point now, int cap_ms);

  std::size_t connection_count() const { return clients_.size(); }
  const ModbusServerStats& stats() const { return stats_; }

 private:
  struct Client {
    int fd = -1;
    std::string peer;
    std::uint32_t address_be = 0;  ///< the peer's IPv4 address, network byte order
    Clock::time_point last_activity;
    bool partial = false;  ///< some bytes of a frame are waiting
    Clock::time_point partial_since;
  };
  struct ContextDeleter {
    void operator()(modbus_t* ctx) const { modbus_free(ctx); }
  };

  ModbusServer(ModbusServerSettings settings, modbus_mapping_t* mapping, Log& log);
  void accept_clients(Clock::time_point now);
  /// Serves the complete frames waiting on `client`; false when it must be closed.
  bool serve_client(Client& client, Clock::time_point now, const WriteHook& on_write);
  bool serve_frame(Client& client, std::size_t frame_bytes, const WriteHook& on_write);
  void close_client(std::size_t index, const std::string& why);
  bool allowed(std::uint32_t address_be) const;
  bool is_plc(std::uint32_t address_be) const;
  /// Makes room for a newcomer from `address_be` when the table or its address is full: the
  /// index of the connection to drop, -1 when none needs to go, -2 when the newcomer is refused.
  std::ptrdiff_t slot_for(std::uint32_t address_be) const;
  /// An exception reply for a request whose function code has its high bit set: libmodbus adds
  /// 0x80 and wraps (0x83 -> 0x03), which reads as a normal reply to a request never sent.
  bool reply_high_function_exception(const Client& client, const std::uint8_t* req,
                                     unsigned exception);

  ModbusServerSettings settings_;
  modbus_mapping_t* mapping_;
  Log& log_;
  std::unique_ptr<modbus_t, ContextDeleter> ctx_;
  int listen_fd_ = -1;
  int port_ = 0;
  std::vector<std::uint32_t> allowed_;  ///< network byte order
  std::vector<std::uint32_t> plc_;      ///< network byte order
  std::vector<Client> clients_;
  ModbusServerStats stats_;
};

}  // namespace springscan::daemon
