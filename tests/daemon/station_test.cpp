// The whole station in-process (event loop, Modbus server, machine, runner, store) with the
// test scanner and analysis, driven by the simulated PLC over loopback.
#include "daemon/station.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <mutex>
#include <thread>

#include "simulators/plc_client.hpp"
#include "test_rig.hpp"

namespace springscan::daemon {
namespace {

using simulators::PlcClient;
using simulators::PlcClientSettings;
using testing::PlaneScanner;
using testing::TempDir;

/// A station running on its own thread; stopped and joined by the destructor.
class RunningStation {
 public:
  RunningStation(const std::string& report_dir, PlaneScanner& scanner)
      : log_(LogLevel::kError, nullptr, false) {
    StationSettings settings;
    settings.modbus.bind_address = "127.0.0.1";
    settings.modbus.port = 0;
    settings.machine.known_parts = {3, 4};
    settings.reports.directory = report_dir;
    settings.runner.probe_interval_s = 0.05;
    auto station = Station::create(
        settings, scanner,
        [](std::uint16_t, const analysis::PointCloud& scan) {
          return testing::plane_analysis(scan, 0.1);
        },
        log_,
        [this](const std::string& message) {
          std::lock_guard lock(mutex_);
          notes_.push_back(message);
        });
    if (!station) throw std::runtime_error(station.message());
    station_ = std::move(*station);
    thread_ = std::thread([this] { station_->run(stop_); });
  }
  ~RunningStation() {
    stop_ = true;
    thread_.join();
  }
  std::unique_ptr<PlcClient> plc() const {
    PlcClientSettings settings;
    settings.port = station_->port();
    settings.step_timeout_s = 20.0;
    auto client = PlcClient::connect(settings);
    if (!client) throw std::runtime_error(client.message());
    return std::move(*client);
  }
  std::uint16_t boot_id() const { return station_->boot_id(); }
  bool notified(const std::string& text) {
    std::lock_guard lock(mutex_);
    for (const auto& n : notes_) {
      if (n.find(text) != std::string::npos) return true;
    }
    return false;
  }

 private:
  Log log_;
  std::unique_ptr<Station> station_;
  std::atomic<bool> stop_{false};
  std::mutex mutex_;
  std::vector<std::string> notes_;
  std::thread thread_;
};

class StationTest : public ::testing::Test {
 protected:
  StationTest() : dir_("springscan-station") {}
  std::string reports() const { return dir_.str() + "/reports"; }
  /// Waits until the station sees the scanner (the runner probes it on its own thread).
  static void wait_online(PlcClient& plc) {
    ASSERT_TRUE(
        plc.wait_for([](const auto& s) { return s.bit(regs::kDiScannerOnline); }, "SCANNER_ONLINE")
            .ok());
  }
  TempDir dir_;
  PlaneScanner scanner_;
};

TEST_F(StationTest, GoodPartThenBadPartThroughTheRegisters) {
  RunningStation station(reports(), scanner_);
  auto plc = station.plc();
  wait_online(*plc);
  EXPECT_TRUE(station.notified("READY=1"));
  auto good = plc->run_cycle(11, 3);
  ASSERT_TRUE(good.ok()) << good.message();
  ASSERT_TRUE(good->accepted);
  EXPECT_TRUE(good->part_ok);
  EXPECT_EQ(good->result.seq, 1);
  EXPECT_EQ(good->result.part_id, 3);
  EXPECT_EQ(good->result.job_id, 11);
  EXPECT_EQ(good->result.code, regs::ResultCode::kOk);
  EXPECT_EQ(good->result.max_deviation_um, 50);  // the scanner lifted the sheet by 0.05 mm
  ASSERT_EQ(good->result.vectors_um.size(), 20u);
  EXPECT_EQ(good->result.vectors_um[19][2], -50);
  EXPECT_EQ(good->result.reads, 3);  // result block + 160 registers in chunks of <= 120
  EXPECT_TRUE(std::filesystem::exists(reports() + "/r000000000001/report.json"));
  scanner_.offset_mm = 0.25;
  auto bad = plc->run_cycle(12, 4);
  ASSERT_TRUE(bad.ok()) << bad.message();
  EXPECT_FALSE(bad->part_ok);
  EXPECT_EQ(bad->result.seq, 2);
  EXPECT_EQ(bad->result.code, regs::ResultCode::kFormNok);
  ASSERT_EQ(bad->result.springback_mdeg.size(), 1u);
  EXPECT_EQ(bad->result.springback_mdeg[0], 2500);
  EXPECT_EQ(bad->result.bend_flags[0], regs::kBendMeasured);  // measured, not passed
}

TEST_F(StationTest, UnplugMidScanFaultsThenResetAndNextCyclePasses) {
  RunningStation station(reports(), scanner_);
  auto plc = station.plc();
  wait_online(*plc);
  scanner_.unplug_next_scan = true;
  auto failed = plc->run_cycle(1, 3, false);
  ASSERT_TRUE(failed.ok()) << failed.message();
  EXPECT_EQ(failed->result.code, regs::ResultCode::kScanFailed);
  EXPECT_EQ(failed->error_code, static_cast<std::uint16_t>(regs::ErrorCode::kScanFailed));
  EXPECT_FALSE(failed->part_ok);
  auto status = plc->read_status();
  EXPECT_EQ(status->live[regs::kIrState], static_cast<std::uint16_t>(regs::State::kFault));
  EXPECT_EQ(status->live[regs::kIrErrorDetail],
            static_cast<std::uint16_t>(regs::ErrorDetail::kDeviceGone));
  scanner_.present = true;  // replugged
  ASSERT_TRUE(plc->reset_errors().ok());
  wait_online(*plc);
  auto next = plc->run_cycle(2, 3);
  ASSERT_TRUE(next.ok()) << next.message();
  EXPECT_TRUE(next->part_ok);
  EXPECT_EQ(next->result.seq, 2);
}

TEST_F(StationTest, TriggerWhileBusyIsRefusedAndNothingIsQueued) {
  RunningStation station(reports(), scanner_);
  auto plc = station.plc();
  auto other = station.plc();
  wait_online(*plc);
  scanner_.close_gate();  // the scan "runs" until the gate opens
  const auto start = std::chrono::steady_clock::now();
  auto first = plc->trigger(1, 3);
  ASSERT_TRUE(first.ok() && first->accepted);
  auto second = other->trigger(2, 3);
  ASSERT_TRUE(second.ok()) << second.message();
  EXPECT_FALSE(second->accepted);
  EXPECT_EQ(second->reject_code, regs::RejectCode::kBusy);
  scanner_.open_gate();
  auto result = plc->wait_result(*first, start);
  ASSERT_TRUE(result.ok()) << result.message();
  EXPECT_EQ(result->result.seq, 1);
  EXPECT_EQ(result->result.job_id, 1);
  ASSERT_TRUE(plc->acknowledge().ok());
  auto status = plc->read_status();
  EXPECT_EQ(status->live[regs::kIrTriggerCount], 1);
  EXPECT_EQ(scanner_.scans.load(), 1);
}

TEST_F(StationTest, PlcReconnectMidHandshakeLosesAndDuplicatesNothing) {
  RunningStation station(reports(), scanner_);
  {
    auto plc = station.plc();
    wait_online(*plc);
    scanner_.close_gate();
    auto first = plc->trigger(7, 3);
    ASSERT_TRUE(first.ok() && first->accepted);
  }  // the PLC drops the connection while the scan runs
  scanner_.open_gate();
  auto plc = station.plc();
  auto result = plc->wait_result(simulators::CycleResult{}, std::chrono::steady_clock::now());
  ASSERT_TRUE(result.ok()) << result.message();
  EXPECT_EQ(result->result.seq, 1);
  EXPECT_EQ(result->result.job_id, 7);
  ASSERT_TRUE(plc->acknowledge().ok());
  auto next = plc->run_cycle(8, 3);
  ASSERT_TRUE(next.ok()) << next.message();
  EXPECT_EQ(next->result.seq, 2);  // one result per trigger, none lost, none repeated
  EXPECT_EQ(scanner_.scans.load(), 2);
}

TEST_F(StationTest, RestartShowsTheLastResultAsNotValidUnderANewBootId) {
  std::uint16_t first_boot = 0;
  {
    RunningStation station(reports(), scanner_);
    first_boot = station.boot_id();
    auto plc = station.plc();
    wait_online(*plc);
    ASSERT_TRUE(plc->run_cycle(5, 3, false).ok());  // not acknowledged before the "crash"
  }
  RunningStation station(reports(), scanner_);
  auto plc = station.plc();
  auto status = plc->read_status();
  ASSERT_TRUE(status.ok());
  EXPECT_NE(status->live[regs::kIrBootId], first_boot);
  EXPECT_NE(status->live[regs::kIrBootId], 0);
  EXPECT_FALSE(status->bit(regs::kDiResultValid));
  // Coils and holding registers start at 0 after a restart: the PLC writes TRIGGER_ENABLE,
  // JOB_ID, PART_ID and PAGE_SELECT again (the old ones were 1, 5, 3).
  std::uint8_t coils[regs::kCoilCount] = {1, 1, 1, 1};
  ASSERT_EQ(modbus_read_bits(plc->context(), 0, regs::kCoilCount, coils), regs::kCoilCount);
  for (const std::uint8_t coil : coils) EXPECT_EQ(coil, 0);
  std::uint16_t holding[regs::kHrWritableCount] = {1, 1, 1, 1, 1};
  ASSERT_EQ(modbus_read_registers(plc->context(), 0, regs::kHrWritableCount, holding),
            regs::kHrWritableCount);
  for (const std::uint16_t value : holding) EXPECT_EQ(value, 0);
  auto shown = plc->read_result();
  EXPECT_EQ(shown->seq, 1);
  EXPECT_EQ(shown->job_id, 5);
  wait_online(*plc);
  auto next = plc->run_cycle(6, 3);
  ASSERT_TRUE(next.ok()) << next.message();
  EXPECT_EQ(next->result.seq, 2);  // sequence numbers continue across restarts
}

}  // namespace
}  // namespace springscan::daemon
