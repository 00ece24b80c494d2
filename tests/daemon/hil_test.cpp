// Hardware in the loop, the normal cycle and the Modbus side (hil_rig.hpp): the real springscand
// process, the production libusb driver against the emulated scanner, the real analysis on the
// demo part's CAD file, the simulated PLC and Debian's mbpoll over loopback TCP.
#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <fstream>
#include <sstream>
#include <thread>

#include "hil_rig.hpp"

namespace springscan::daemon {
namespace {

using testing::HilTest;

/// mbpoll against the daemon: `options` are mbpoll's (0-based addresses with -0, one poll);
/// `values`, when given, are written instead of read.
std::pair<int, std::string> mbpoll(int port, const std::string& options,
                                   const std::string& values = "") {
  return testing::run_command("mbpoll -m tcp -a 1 -0 -1 -o 10 -p " + std::to_string(port) + " " +
                              options + " 127.0.0.1 " + values);
}

/// mbpoll writes `values` from `first` in table `type` (0 coils, 4 holding registers).
void mbpoll_write(int port, int type, int first, const std::string& values) {
  const auto [status, output] =
      mbpoll(port, "-t " + std::to_string(type) + " -r " + std::to_string(first), values);
  ASSERT_EQ(status, 0) << output;
}

/// mbpoll polls the discrete inputs until `bit` reads `value`, writing PLC_HEARTBEAT each
/// time as a PLC does (the daemon watches it). False after `timeout_s`.
bool mbpoll_wait_bit(int port, int bit, bool value, int& heartbeat, double timeout_s = 180.0) {
  const auto deadline = std::chrono::steady_clock::now() +
                        std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                            std::chrono::duration<double>(timeout_s));
  while (std::chrono::steady_clock::now() < deadline) {
    mbpoll(port, "-t 4 -r 3", std::to_string(++heartbeat));
    const auto [status, output] = mbpoll(port, "-t 1 -r 0 -c 10");
    const auto bits = testing::mbpoll_values(output);
    if (status == 0 && bits.count(bit) != 0 && (bits.at(bit) != 0) == value) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));  // a PLC's poll period
  }
  return false;
}

TEST_F(HilTest, GoodPartPassesWithItsSpringbackAndMbpollRunsTheHandshake) {
  emulate(testing::kGoodSpringback);
  auto daemon = start_daemon();
  auto client = plc(daemon->port());
  wait_online(*client);
  auto cycle = client->run_cycle(21, 1);
  ASSERT_TRUE(cycle.ok()) << cycle.message();
  ASSERT_TRUE(cycle->accepted);
  EXPECT_EQ(cycle->result.seq, 1);
  EXPECT_EQ(cycle->result.job_id, 21);
  EXPECT_EQ(cycle->result.part_id, 1);
  EXPECT_EQ(cycle->result.code, regs::ResultCode::kOk);
  EXPECT_TRUE(cycle->part_ok);
  // The deviation in the registers is the report's, in um (springback included, so more
  // than the 0.02 mm noise).
  const v1::InspectionReport first = report(1);
  EXPECT_NEAR(cycle->result.rms_deviation_um, first.deviation().rms() * 1000.0, 1.0);
  EXPECT_NEAR(cycle->result.max_deviation_um,
              std::max(-first.deviation().min(), first.deviation().max()) * 1000.0, 1.0);
  EXPECT_LT(first.deviation().rms(), 0.2);
  EXPECT_FALSE(cycle->result.vectors_um.empty());
  EXPECT_TRUE(first.verdict().pass());
  expect_springback(first, testing::kGoodSpringback, 0.05);
  expect_registers_match(cycle->result, first);
  // The tool designer's files in the record: a row per control point, the supported ones
  // being the report's compensation vectors (docs/report-format.md).
  {
    std::ifstream csv(reports() + "/r000000000001/compensation.csv");
    ASSERT_TRUE(csv) << "no compensation.csv in the record";
    std::string line;
    std::getline(csv, line);  // the header
    int supported = 0;
    while (std::getline(csv, line)) {
      std::stringstream fields(line);
      std::string field;
      for (int column = 0; column <= 7; ++column) std::getline(fields, field, ',');
      supported += field == "1" ? 1 : 0;  // column 7: supported
    }
    EXPECT_GT(first.compensation_size(), 0);
    EXPECT_EQ(supported, first.compensation_size());
    EXPECT_TRUE(std::filesystem::exists(reports() + "/r000000000001/compensation.ply"));
  }

  // A third-party client runs the next handshake: Debian's mbpoll, one request per call.
  const int port = daemon->port();
  int heartbeat = 1000;
  mbpoll_write(port, 4, regs::kHrJobId, "22 1");           // JOB_ID 22, PART_ID 1 (FC16)
  mbpoll_write(port, 0, regs::kCoilTriggerEnable, "1 1");  // TRIGGER_ENABLE, TRIGGER (FC15)
  ASSERT_TRUE(mbpoll_wait_bit(port, regs::kDiTriggerAck, true, heartbeat));
  mbpoll_write(port, 0, regs::kCoilTrigger, "0");  // TRIGGER drops (FC05)
  ASSERT_TRUE(mbpoll_wait_bit(port, regs::kDiResultValid, true, heartbeat));
  const auto [status, output] = mbpoll(port, "-t 3:hex -r 100 -c 44");  // up to bend record 3
  ASSERT_EQ(status, 0) << output;
  const auto words = testing::mbpoll_values(output);
  ASSERT_EQ(words.size(), 44u) << output;
  EXPECT_EQ(words.at(regs::kIrResultSeq), 2u);
  EXPECT_EQ(words.at(regs::kIrResultJobId), 22u);
  EXPECT_EQ(words.at(regs::kIrResultCode), static_cast<unsigned>(regs::ResultCode::kOk));
  const v1::InspectionReport second = report(2);
  ASSERT_EQ(words.at(regs::kIrBendCount), static_cast<unsigned>(second.bends_size()));
  for (int j = 0; j < second.bends_size(); ++j) {  // int32 millidegrees, high word first
    const int at = regs::kIrBendTable + j * regs::kBendRecordSize + regs::kBendSpringback;
    const std::uint16_t pair[2] = {static_cast<std::uint16_t>(words.at(at)),
                                   static_cast<std::uint16_t>(words.at(at + 1))};
    EXPECT_NEAR(regs::decode_int32(pair, regs::WordOrder::kAbcd),
                second.bends(j).springback_deg() * 1000.0, 1.0);
  }
  expect_springback(second, testing::kGoodSpringback, 0.05);
  mbpoll_write(port, 0, regs::kCoilResultAck, "1");
  ASSERT_TRUE(mbpoll_wait_bit(port, regs::kDiResultValid, false, heartbeat));
  mbpoll_write(port, 0, regs::kCoilResultAck, "0");
  EXPECT_EQ(record_count(), 2);
}

TEST_F(HilTest, SpringbackBeyondToleranceFailsWithTheReasonInTheReport) {
  const std::vector<double> produced{2.5, 0.3, 0.6, 0.2};  // bend 0 opens 1.5 deg too far
  emulate(produced);
  auto daemon = start_daemon();
  auto client = plc(daemon->port());
  wait_online(*client);
  auto cycle = client->run_cycle(5, 1);
  ASSERT_TRUE(cycle.ok()) << cycle.message();
  EXPECT_EQ(cycle->result.code, regs::ResultCode::kFormNok);
  EXPECT_FALSE(cycle->part_ok);
  const v1::InspectionReport r = report(1);
  EXPECT_FALSE(r.verdict().pass());
  const std::vector<int> index = expect_springback(r, produced, 0.05);
  ASSERT_EQ(index.size(), 4u);
  expect_registers_match(cycle->result, r);
  std::string failed_bend;
  for (int k = 0; k < r.bends_size(); ++k) {
    const bool opened_too_far = index[static_cast<std::size_t>(k)] == 0;
    EXPECT_EQ(r.bends(k).pass(), !opened_too_far) << "report bend " << r.bends(k).id();
    if (opened_too_far) failed_bend = "bend " + std::to_string(r.bends(k).id()) + " springback";
  }
  ASSERT_EQ(r.verdict().reasons_size(), 1) << r.verdict().DebugString();
  EXPECT_EQ(r.verdict().reasons(0).rfind(failed_bend, 0), 0u) << r.verdict().DebugString();
}

/// A raw TCP connection from `source` (127.0.0.0/8 all reaches loopback).
class RawClient {
 public:
  RawClient(int port, const char* source) {
    fd_ = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
    timeval timeout{30, 0};  // the daemon answers or closes; 30 s is only a safety net
    setsockopt(fd_, SOL_SOCKET, SO_RCVTIMEO, &timeout, sizeof timeout);
    sockaddr_in local{};
    local.sin_family = AF_INET;
    inet_pton(AF_INET, source, &local.sin_addr);
    if (::bind(fd_, reinterpret_cast<sockaddr*>(&local), sizeof local) != 0)
      throw std::runtime_error("bind source failed");
    sockaddr_in addr{};
    addr.sin_family = AF_INET;
    addr.sin_port = htons(static_cast<std::uint16_t>(port));
    inet_pton(AF_INET, "127.0.0.1", &addr.sin_addr);
    if (::connect(fd_, reinterpret_cast<sockaddr*>(&addr), sizeof addr) != 0)
      throw std::runtime_error("raw connect failed");
  }
  ~RawClient() { ::close(fd_); }
  RawClient(const RawClient&) = delete;
  RawClient& operator=(const RawClient&) = delete;
  void send_bytes(const std::vector<std::uint8_t>& bytes) const {
    ASSERT_EQ(::send(fd_, bytes.data(), bytes.size(), MSG_NOSIGNAL),
              static_cast<ssize_t>(bytes.size()));
  }
  /// One reply; empty when the daemon closed the connection.
  std::vector<std::uint8_t> receive() const {
    std::vector<std::uint8_t> buffer(300);
    const ssize_t n = ::recv(fd_, buffer.data(), buffer.size(), 0);
    buffer.resize(n > 0 ? static_cast<std::size_t>(n) : 0);
    return buffer;
  }

 private:
  int fd_ = -1;
};

std::vector<std::uint8_t> adu(const std::vector<std::uint8_t>& pdu) {
  std::vector<std::uint8_t> out = {0x12, 0x34, 0, 0, 0, static_cast<std::uint8_t>(pdu.size() + 1),
                                   1};
  for (const std::uint8_t byte : pdu) out.push_back(byte);
  return out;
}

TEST_F(HilTest, MalformedFramesAndAForeignClientLeaveTheStationServing) {
  emulate(testing::kGoodSpringback);
  auto daemon = start_daemon();
  auto client = plc(daemon->port());
  wait_online(*client);
  {  // not on the allow-list (only 127.0.0.1 is): closed at accept, nothing answered
    RawClient foreign(daemon->port(), "127.0.0.2");
    foreign.send_bytes(adu({4, 0, 0, 0, 1}));
    EXPECT_TRUE(foreign.receive().empty());
  }
  {  // well framed but wrong: exceptions, and the connection stays usable
    RawClient raw(daemon->port(), "127.0.0.1");
    raw.send_bytes(adu({4, 0x03, 0xE8, 0, 126}));  // 126 registers: over FC04's limit
    auto reply = raw.receive();
    ASSERT_EQ(reply.size(), 9u);
    EXPECT_EQ(reply[7], 0x84);
    EXPECT_EQ(reply[8], 3);                                 // ILLEGAL DATA VALUE
    raw.send_bytes(adu({6, 0, regs::kIrResultSeq, 0, 1}));  // write a read-only mirror
    reply = raw.receive();
    ASSERT_EQ(reply.size(), 9u);
    EXPECT_EQ(reply[8], 2);                                        // ILLEGAL DATA ADDRESS
    raw.send_bytes(adu({0x17, 0, 1, 0, 1, 0, 1, 0, 1, 2, 0, 7}));  // FC23 (libmodbus #614)
    reply = raw.receive();
    ASSERT_EQ(reply.size(), 9u);
    EXPECT_EQ(reply[8], 1);  // ILLEGAL FUNCTION
    raw.send_bytes(adu({4, 0, 0, 0, 1}));
    EXPECT_EQ(raw.receive().size(), 11u);
  }
  {  // not Modbus TCP (protocol id 5), and a length of 4096: the connection is closed
    RawClient raw(daemon->port(), "127.0.0.1");
    raw.send_bytes({0, 1, 0, 5, 0, 6, 1, 4, 0, 0, 0, 1});
    EXPECT_TRUE(raw.receive().empty());
    RawClient huge(daemon->port(), "127.0.0.1");
    huge.send_bytes({0, 1, 0, 0, 0x10, 0, 1});
    EXPECT_TRUE(huge.receive().empty());
  }
  // The station kept serving the PLC all along and still inspects.
  auto cycle = client->run_cycle(3, 1);
  ASSERT_TRUE(cycle.ok()) << cycle.message();
  EXPECT_EQ(cycle->result.code, regs::ResultCode::kOk);
  EXPECT_EQ(cycle->result.seq, 1);
  EXPECT_EQ(daemon->stop(SIGTERM), 0);  // exits cleanly
}

}  // namespace
}  // namespace springscan::daemon
