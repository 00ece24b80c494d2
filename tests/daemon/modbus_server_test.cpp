// The Modbus server on loopback port 0 with a real libmodbus client and raw sockets.
#include "daemon/modbus_server.hpp"

#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <memory>
#include <set>
#include <thread>
#include <vector>

#include "daemon/register_image.hpp"

namespace springscan::daemon {
namespace {

using namespace std::chrono_literals;

struct ContextDeleter {
  void operator()(modbus_t* ctx) const {
    modbus_close(ctx);
    modbus_free(ctx);
  }
};
using Context = std::unique_ptr<modbus_t, ContextDeleter>;

/// Runs a server over a register image on its own thread, like the station's loop does.
class ServerHarness {
 public:
  explicit ServerHarness(ModbusServerSettings settings = {},
                         const std::function<void(RegisterImage&)>& prepare = {})
      : image_(regs::WordOrder::kAbcd), log_(LogLevel::kError, nullptr, false) {
    settings.bind_address = "127.0.0.1";
    settings.port = 0;
    if (prepare) prepare(image_);
    auto server = ModbusServer::open(settings, image_.mapping(), log_);
    if (!server) throw std::runtime_error(server.message());
    server_ = std::move(*server);
    thread_ = std::thread([this] {
      while (!stop_) {
        std::vector<pollfd> fds;
        server_->add_poll_fds(fds);
        const int timeout = server_->expire(ModbusServer::Clock::now(), 10);
        poll(fds.data(), fds.size(), timeout);
        server_->service(fds, ModbusServer::Clock::now(), [this] { ++writes_; });
      }
    });
  }
  ~ServerHarness() {
    stop_ = true;
    thread_.join();
  }
  int port() const { return server_->port(); }
  const ModbusServerStats& stats() const { return server_->stats(); }  // after stop only
  int writes() const { return writes_; }

  Context client(const char* address = "127.0.0.1") const {
    Context ctx(modbus_new_tcp(address, port()));
    modbus_set_slave(ctx.get(), 1);
    modbus_set_response_timeout(ctx.get(), 2, 0);
    if (modbus_connect(ctx.get()) != 0) throw std::runtime_error("connect failed");
    return ctx;
  }

 private:
  RegisterImage image_;
  Log log_;
  std::unique_ptr<ModbusServer> server_;
  std::atomic<bool> stop_{false};
  std::atomic<int> writes_{0};
  std::thread thread_;
};

/// A raw TCP connection for frames libmodbus would never send.
class RawClient {
 public:
  explicit RawClient(int port, const char* source = nullptr) {
    fd_ = socket(AF_INET, SOCK_STREAM, 0);
    timeval timeout{5, 0};
    setsockopt(fd_, SOL_SOCKET, SO_RCVTIMEO, &timeout, sizeof timeout);
    if (source != nullptr) {
      sockaddr_in local{};
      local.sin_family = AF_INET;
      inet_pton(AF_INET, source, &local.sin_addr);
      if (bind(fd_, reinterpret_cast<sockaddr*>(&local), sizeof local) != 0) {
        throw std::runtime_error("bind source failed");
      }
    }
    sockaddr_in addr{};
    addr.sin_family = AF_INET;
    addr.sin_port = htons(static_cast<std::uint16_t>(port));
    inet_pton(AF_INET, "127.0.0.1", &addr.sin_addr);
    if (connect(fd_, reinterpret_cast<sockaddr*>(&addr), sizeof addr) != 0) {
      throw std::runtime_error("raw connect failed");
    }
  }
  ~RawClient() { close(fd_); }
  void send_bytes(const std::vector<std::uint8_t>& bytes) const {
    ASSERT_EQ(send(fd_, bytes.data(), bytes.size(), MSG_NOSIGNAL),
              static_cast<ssize_t>(bytes.size()));
  }
  /// Bytes of one reply; empty when the server closed the connection.
  std::vector<std::uint8_t> receive() const {
    std::vector<std::uint8_t> buffer(300);
    const ssize_t n = recv(fd_, buffer.data(), buffer.size(), 0);
    buffer.resize(n > 0 ? static_cast<std::size_t>(n) : 0);
    return buffer;
  }

 private:
  int fd_ = -1;
};

std::vector<std::uint8_t> frame(std::vector<std::uint8_t> pdu, std::uint8_t unit = 1) {
  const auto length = static_cast<std::uint8_t>(pdu.size() + 1);
  std::vector<std::uint8_t> out = {0xAB, 0xCD, 0, 0, 0, length, unit};
  for (const std::uint8_t byte : pdu) out.push_back(byte);  // (insert trips GCC 12 -Warray-bounds)
  return out;
}

void prepare_known_values(RegisterImage& image) {
  ResultBlock block;
  block.seq = 17;
  block.code = regs::ResultCode::kOk;
  block.vectors.resize(200, VectorRow{0.001, 0.002, -0.003});
  image.publish_result(block);
  MachineStatus status;
  status.scanner_online = true;
  status.ready = true;
  image.publish_status(status, LiveValues{999, 0, 0});
}

TEST(ModbusServer, ServesEveryWhitelistedFunctionCode) {
  ServerHarness server({}, prepare_known_values);
  Context ctx = server.client();
  modbus_t* c = ctx.get();
  // FC05 + FC01
  ASSERT_EQ(modbus_write_bit(c, regs::kCoilTriggerEnable, 1), 1);
  std::uint8_t bits[16] = {};
  ASSERT_EQ(modbus_read_bits(c, 0, regs::kCoilCount, bits), regs::kCoilCount);
  EXPECT_EQ(bits[0], 1);
  EXPECT_EQ(bits[1], 0);
  // FC15
  const std::uint8_t coils[4] = {0, 1, 1, 0};
  ASSERT_EQ(modbus_write_bits(c, 0, 4, coils), 4);
  ASSERT_EQ(modbus_read_bits(c, 0, 4, bits), 4);
  EXPECT_EQ(bits[0], 0);
  EXPECT_EQ(bits[2], 1);
  // FC02
  ASSERT_EQ(modbus_read_input_bits(c, 0, regs::kDiCount, bits), regs::kDiCount);
  EXPECT_EQ(bits[regs::kDiReady], 1);
  EXPECT_EQ(bits[regs::kDiScannerOnline], 1);
  EXPECT_EQ(bits[regs::kDiBusy], 0);
  // FC06 + FC16 + FC03
  ASSERT_EQ(modbus_write_register(c, regs::kHrJobId, 4242), 1);
  const std::uint16_t values[3] = {11, 12, 13};
  ASSERT_EQ(modbus_write_registers(c, regs::kHrPartId, 3, values), 3);
  std::uint16_t regs_read[125] = {};
  ASSERT_EQ(modbus_read_registers(c, 0, regs::kHrWritableCount, regs_read), regs::kHrWritableCount);
  EXPECT_EQ(regs_read[regs::kHrJobId], 4242);
  EXPECT_EQ(regs_read[regs::kHrPartId], 11);
  EXPECT_EQ(regs_read[regs::kHrPageSelect], 13);
  // FC04: live block and a 120-register chunk of the vector block.
  ASSERT_EQ(modbus_read_input_registers(c, 0, regs::kLiveCount, regs_read), regs::kLiveCount);
  EXPECT_EQ(regs_read[regs::kIrBootId], 999);
  EXPECT_EQ(regs_read[regs::kIrEndianProbe], 0x0102);
  EXPECT_EQ(regs_read[regs::kIrEndianProbe + 1], 0x0304);
  ASSERT_EQ(modbus_read_input_registers(c, regs::kIrVectors + 120, 120, regs_read), 120);
  EXPECT_EQ(regs_read[regs::kVectorIndex], 15);  // record 15 starts the second chunk
  EXPECT_EQ(regs::decode_int32(regs_read + regs::kVectorDz, regs::WordOrder::kAbcd), -3);
  // FC03 reads the same result through the read-only mirror.
  ASSERT_EQ(modbus_read_registers(c, regs::kIrResultSeq, 1, regs_read), 1);
  EXPECT_EQ(regs_read[0], 17);
  EXPECT_EQ(server.writes(), 4);  // FC05, FC15, FC06, FC16
}

TEST(ModbusServer, AnswersExceptionsForBadAddressesFunctionsAndReadOnlyWrites) {
  ServerHarness server;
  Context ctx = server.client();
  modbus_t* c = ctx.get();
  std::uint16_t r[130];
  std::uint8_t b[16];
  EXPECT_EQ(modbus_read_input_registers(c, regs::kLiveCount, 1, r), -1);
  EXPECT_EQ(errno, EMBXILADD);
  EXPECT_EQ(modbus_read_input_registers(c, 0xFFFF, 1, r), -1);
  EXPECT_EQ(errno, EMBXILADD);
  EXPECT_EQ(modbus_read_bits(c, 0, 5, b), -1);
  EXPECT_EQ(errno, EMBXILADD);
  EXPECT_EQ(modbus_write_register(c, regs::kIrResultSeq, 1), -1);  // read-only mirror
  EXPECT_EQ(errno, EMBXILADD);
  EXPECT_EQ(modbus_write_register(c, regs::kHrLiveMirror, 1), -1);
  EXPECT_EQ(errno, EMBXILADD);
  EXPECT_EQ(modbus_write_bit(c, regs::kCoilCount, 1), -1);
  EXPECT_EQ(errno, EMBXILADD);
  std::uint8_t id[64];
  EXPECT_EQ(modbus_report_slave_id(c, sizeof id, id), -1);  // FC17
  EXPECT_EQ(errno, EMBXILFUN);
  const std::uint16_t one = 1;
  EXPECT_EQ(modbus_write_and_read_registers(c, 1, 1, &one, 0, 1, r), -1);  // FC23
  EXPECT_EQ(errno, EMBXILFUN);
  modbus_set_slave(c, 9);
  EXPECT_EQ(modbus_read_input_registers(c, 0, 1, r), -1);
  EXPECT_EQ(errno, EMBXGTAR);
  // The connection survives every exception.
  modbus_set_slave(c, 1);
  EXPECT_EQ(modbus_read_input_registers(c, 0, 1, r), 1);
}

TEST(ModbusServer, UnitIdZeroIsAnsweredAndPageSelectPastTheLastPageIsRefused) {
  ServerHarness server;
  Context ctx = server.client();
  modbus_t* c = ctx.get();
  modbus_set_slave(c, 0);  // what pymodbus sends by default
  std::uint16_t r[regs::kHrWritableCount] = {};
  ASSERT_EQ(modbus_read_input_registers(c, regs::kIrMapVersion, 1, r), 1);
  EXPECT_EQ(r[0], regs::kMapVersion);
  ASSERT_EQ(modbus_write_register(c, regs::kHrPageSelect, regs::kPageCount - 1), 1);
  EXPECT_EQ(modbus_write_register(c, regs::kHrPageSelect, regs::kPageCount), -1);
  EXPECT_EQ(errno, EMBXILVAL);
  const std::uint16_t ids[4] = {7, 1, 3, 500};  // JOB_ID, PART_ID, PLC_HEARTBEAT, PAGE_SELECT
  EXPECT_EQ(modbus_write_registers(c, regs::kHrJobId, 4, ids), -1);
  EXPECT_EQ(errno, EMBXILVAL);
  ASSERT_EQ(modbus_read_registers(c, 0, regs::kHrWritableCount, r), regs::kHrWritableCount);
  EXPECT_EQ(r[regs::kHrJobId], 0);  // nothing of the refused write was applied
  EXPECT_EQ(r[regs::kHrPageSelect], regs::kPageCount - 1);
}

TEST(ModbusServer, MalformedFramesGetExceptionsOrAClosedConnection) {
  ServerHarness server;
  {
    RawClient raw(server.port());
    raw.send_bytes(frame({4, 0x03, 0xE8, 0, 126}));  // 126 registers: over the FC04 limit
    const auto reply = raw.receive();
    ASSERT_EQ(reply.size(), 9u);
    EXPECT_EQ(reply[0], 0xAB);  // transaction id echoed
    EXPECT_EQ(reply[7], 0x84);
    EXPECT_EQ(reply[8], MODBUS_EXCEPTION_ILLEGAL_DATA_VALUE);
    raw.send_bytes(frame({16, 0, 1, 0, 2, 4, 0, 7}));  // byte count promises more than sent
    const auto reply2 = raw.receive();
    ASSERT_EQ(reply2.size(), 9u);
    EXPECT_EQ(reply2[8], MODBUS_EXCEPTION_ILLEGAL_DATA_VALUE);
    raw.send_bytes(
        frame({0x07}));  // diagnostics short frame (libmodbus issue 837): refused, not parsed
    EXPECT_EQ(raw.receive().at(8), MODBUS_EXCEPTION_ILLEGAL_FUNCTION);
  }
  {
    RawClient raw(server.port());
    raw.send_bytes({0, 1, 0, 5, 0, 6, 1, 4, 0, 0, 0, 1});  // protocol id 5: not Modbus
    EXPECT_TRUE(raw.receive().empty());
  }
  {
    RawClient raw(server.port());
    raw.send_bytes({0, 1, 0, 0, 0x10, 0, 1});  // length 4096
    EXPECT_TRUE(raw.receive().empty());
  }
  // The server still serves a well-behaved client.
  Context ctx = server.client();
  std::uint16_t r;
  EXPECT_EQ(modbus_read_input_registers(ctx.get(), 0, 1, &r), 1);
}

TEST(ModbusServer, ClientNotOnTheAllowListIsClosedAtAccept) {
  ModbusServerSettings settings;
  settings.allowed_clients = {"127.0.0.2"};
  ServerHarness server(settings);
  {
    RawClient refused(server.port());  // source 127.0.0.1
    refused.send_bytes(frame({4, 0, 0, 0, 1}));
    EXPECT_TRUE(refused.receive().empty());
  }
  RawClient allowed(server.port(), "127.0.0.2");
  allowed.send_bytes(frame({4, 0, 0, 0, 1}));
  EXPECT_EQ(allowed.receive().size(), 11u);
}

TEST(ModbusServer, SlowPartialFrameDoesNotStarveOthersAndIsClosed) {
  ModbusServerSettings settings;
  settings.partial_frame_timeout_s = 0.3;
  ServerHarness server(settings);
  RawClient slow(server.port());
  slow.send_bytes({0, 1, 0, 0});  // half an MBAP header, then silence
  Context ctx = server.client();
  std::uint16_t r;
  for (int i = 0; i < 20; ++i) {
    ASSERT_EQ(modbus_read_input_registers(ctx.get(), 0, 1, &r), 1) << "request " << i;
  }
  EXPECT_TRUE(slow.receive().empty());  // closed after the partial-frame timeout
}

TEST(ModbusServer, ANewcomerTakesTheSlotOfTheLeastRecentlyActive) {
  ModbusServerSettings settings;
  settings.max_connections = 2;
  ServerHarness server(settings);
  Context a = server.client();
  Context b = server.client();
  std::uint16_t r;
  ASSERT_EQ(modbus_read_input_registers(b.get(), 0, 1, &r), 1);
  std::this_thread::sleep_for(20ms);
  ASSERT_EQ(modbus_read_input_registers(a.get(), 0, 1, &r), 1);  // b is now the stalest
  RawClient third(server.port());
  third.send_bytes(frame({4, 0, 0, 0, 1}));
  EXPECT_EQ(third.receive().size(), 11u);
  EXPECT_EQ(modbus_read_input_registers(a.get(), 0, 1, &r), 1);
  EXPECT_EQ(modbus_read_input_registers(b.get(), 0, 1, &r), -1);  // closed for the newcomer
}

// A prober (or a PLC's half-open old sessions) holding 32 idle connections never locks the
// PLC out: it reads within 100 ms, and again once they are released.
TEST(ModbusServer, ThirtyTwoIdleConnectionsDoNotLockThePlcOut) {
  ServerHarness server;  // max_connections 4, every address a PLC address
  std::vector<std::unique_ptr<RawClient>> idle;
  for (int i = 0; i < 32; ++i) idle.push_back(std::make_unique<RawClient>(server.port()));
  std::this_thread::sleep_for(50ms);  // the server has seen them all
  const auto read_as_plc = [&server] {
    const auto start = std::chrono::steady_clock::now();
    Context plc = server.client();
    std::uint16_t r;
    EXPECT_EQ(modbus_read_input_registers(plc.get(), 0, 1, &r), 1);
    return std::chrono::steady_clock::now() - start;
  };
  EXPECT_LT(read_as_plc(), 100ms);
  idle.clear();
  std::this_thread::sleep_for(20ms);
  EXPECT_LT(read_as_plc(), 100ms);
}

TEST(ModbusServer, OtherAddressesNeverTakeThePlcsSlot) {
  ModbusServerSettings settings;
  settings.max_connections = 2;
  settings.plc_clients = {"127.0.0.1"};
  ServerHarness server(settings);
  Context plc = server.client();  // from 127.0.0.1
  std::uint16_t r;
  ASSERT_EQ(modbus_read_input_registers(plc.get(), 0, 1, &r), 1);
  // Other loopback addresses (127.0.0.2) come and go: they share the one remaining slot.
  for (int i = 0; i < 5; ++i) {
    RawClient other(server.port(), "127.0.0.2");
    other.send_bytes(frame({4, 0, 0, 0, 1}));
    EXPECT_EQ(other.receive().size(), 11u) << i;
  }
  std::this_thread::sleep_for(20ms);
  EXPECT_EQ(modbus_read_input_registers(plc.get(), 0, 1, &r), 1);
  // Both slots held by the PLC: a non-PLC newcomer is refused, a PLC newcomer is served.
  Context plc2 = server.client();
  ASSERT_EQ(modbus_read_input_registers(plc2.get(), 0, 1, &r), 1);
  RawClient refused(server.port(), "127.0.0.2");
  refused.send_bytes(frame({4, 0, 0, 0, 1}));
  EXPECT_TRUE(refused.receive().empty());
  EXPECT_EQ(modbus_read_input_registers(plc.get(), 0, 1, &r), 1);
  EXPECT_EQ(modbus_read_input_registers(plc2.get(), 0, 1, &r), 1);
}

TEST(ModbusServer, PerAddressLimitReplacesThatAddresssStalestConnection) {
  ModbusServerSettings settings;
  settings.max_connections = 4;
  settings.max_connections_per_address = 2;
  ServerHarness server(settings);
  RawClient other(server.port(), "127.0.0.3");
  other.send_bytes(frame({4, 0, 0, 0, 1}));
  ASSERT_EQ(other.receive().size(), 11u);
  std::vector<std::unique_ptr<RawClient>> same;
  for (int i = 0; i < 4; ++i) {
    same.push_back(std::make_unique<RawClient>(server.port(), "127.0.0.2"));
    same.back()->send_bytes(frame({4, 0, 0, 0, 1}));
    ASSERT_EQ(same.back()->receive().size(), 11u);
    std::this_thread::sleep_for(5ms);
  }
  // The two oldest of 127.0.0.2 made room for its newer two; 127.0.0.3 kept its slot.
  same[0]->send_bytes(frame({4, 0, 0, 0, 1}));
  EXPECT_TRUE(same[0]->receive().empty());
  same[3]->send_bytes(frame({4, 0, 0, 0, 1}));
  EXPECT_EQ(same[3]->receive().size(), 11u);
  other.send_bytes(frame({4, 0, 0, 0, 1}));
  EXPECT_EQ(other.receive().size(), 11u);
}

// Modbus Application Protocol V1.1b3 section 7 and Messaging on TCP/IP section 3.1.3: an
// exception reply is the MBAP header (transaction id and unit id echoed, protocol 0, length
// 3), the function code with its high bit set, and one exception code.
void expect_exception_reply(const std::vector<std::uint8_t>& request,
                            const std::vector<std::uint8_t>& reply, std::uint8_t exception) {
  ASSERT_EQ(reply.size(), 9u);
  EXPECT_EQ(reply[0], request[0]);
  EXPECT_EQ(reply[1], request[1]);
  EXPECT_EQ(reply[2], 0);
  EXPECT_EQ(reply[3], 0);
  EXPECT_EQ(reply[4], 0);
  EXPECT_EQ(reply[5], 3);
  EXPECT_EQ(reply[6], request[6]);
  EXPECT_EQ(reply[7], request[7] | 0x80) << "function " << int(request[7]);
  EXPECT_EQ(reply[8], exception);
}

TEST(ModbusServer, EveryExceptionReplyFollowsTheSpec) {
  ServerHarness server;
  RawClient raw(server.port());
  const std::set<int> served = {1, 2, 3, 4, 5, 6, 15, 16};
  for (int function = 0; function <= 0xFF; ++function) {
    if (served.count(function) != 0) continue;
    const auto request = frame({static_cast<std::uint8_t>(function), 0, 0, 0, 1});
    raw.send_bytes(request);
    expect_exception_reply(request, raw.receive(), MODBUS_EXCEPTION_ILLEGAL_FUNCTION);
  }
  const std::vector<std::pair<std::vector<std::uint8_t>, std::uint8_t>> cases = {
      {frame({4, 0x27, 0x0F, 0, 1}), MODBUS_EXCEPTION_ILLEGAL_DATA_ADDRESS},       // 9999: no map
      {frame({6, 0x00, 0x64, 0, 1}), MODBUS_EXCEPTION_ILLEGAL_DATA_ADDRESS},       // read-only
      {frame({3, 0, 0, 0, 0}), MODBUS_EXCEPTION_ILLEGAL_DATA_VALUE},               // 0 registers
      {frame({4, 0, 0, 0, 126}), MODBUS_EXCEPTION_ILLEGAL_DATA_VALUE},             // > 125
      {frame({1, 0, 0, 0x07, 0xD1}), MODBUS_EXCEPTION_ILLEGAL_DATA_VALUE},         // > 2000 bits
      {frame({5, 0, 0, 0x12, 0x34}), MODBUS_EXCEPTION_ILLEGAL_DATA_VALUE},         // coil value
      {frame({16, 0, 1, 0, 2, 3, 0, 7, 0}), MODBUS_EXCEPTION_ILLEGAL_DATA_VALUE},  // byte count
      {frame({4, 0, 0, 0, 1}, 9), MODBUS_EXCEPTION_GATEWAY_TARGET},                // unit 9
  };
  for (const auto& [request, exception] : cases) {
    raw.send_bytes(request);
    expect_exception_reply(request, raw.receive(), exception);
  }
}

TEST(ModbusServer, PipelinedRequestsInOneSegmentAreAllAnswered) {
  ServerHarness server;
  RawClient raw(server.port());
  auto both = frame({4, 0, 0, 0, 1});
  const auto second = frame({4, 0, 1, 0, 1});
  for (const std::uint8_t byte : second) both.push_back(byte);
  raw.send_bytes(both);
  std::vector<std::uint8_t> replies;
  while (replies.size() < 22) {
    const auto part = raw.receive();
    ASSERT_FALSE(part.empty());
    for (const std::uint8_t byte : part) replies.push_back(byte);
  }
  EXPECT_EQ(replies.size(), 22u);
}

TEST(ModbusServer, OpenFailsWithAClearMessage) {
  RegisterImage image(regs::WordOrder::kAbcd);
  Log log(LogLevel::kError, nullptr, false);
  ModbusServerSettings settings;
  settings.bind_address = "not-an-address";
  auto server = ModbusServer::open(settings, image.mapping(), log);
  ASSERT_FALSE(server.ok());
  EXPECT_NE(server.message().find("modbus.bind_address"), std::string::npos);
  settings.bind_address = "127.0.0.1";
  settings.allowed_clients = {"300.1.1.1"};
  EXPECT_NE(ModbusServer::open(settings, image.mapping(), log).message().find("300.1.1.1"),
            std::string::npos);
}

}  // namespace
}  // namespace springscan::daemon
