// Hardware in the loop, the faults (hil_rig.hpp): the scanner unplugged mid-scan and plugged
// back, a trigger while busy, the PLC reconnecting mid-handshake, kill -9 of the daemon during
// an analysis, SIGTERM while a scan waits on a silent device, and each device fault reaching the
// PLC as its ERROR_DETAIL.
#include <csignal>
#include <set>
#include <thread>

#include "hil_rig.hpp"

namespace springscan::daemon {
namespace {

using testing::HilTest;

bool state_is(const simulators::StationStatus& s, regs::State state) {
  return s.live[regs::kIrState] == static_cast<std::uint16_t>(state);
}

TEST_F(HilTest, UnplugMidScanIsAFaultAndAfterResetTheNextCyclePasses) {
  testing::HilDevice device;
  device.faults.unplug_at_fraction = 0.5;  // the cable is pulled half way through the scan
  emulate(testing::kGoodSpringback, device);
  auto daemon = start_daemon();
  auto client = plc(daemon->port());
  wait_online(*client);
  auto failed = client->run_cycle(1, 1, false);
  ASSERT_TRUE(failed.ok()) << failed.message();
  EXPECT_EQ(failed->result.code, regs::ResultCode::kScanFailed);
  EXPECT_FALSE(failed->part_ok);
  EXPECT_EQ(failed->error_code, static_cast<std::uint16_t>(regs::ErrorCode::kScanFailed));
  auto status = client->read_status();
  ASSERT_TRUE(status.ok());
  EXPECT_TRUE(state_is(*status, regs::State::kFault));
  EXPECT_EQ(status->live[regs::kIrErrorDetail],
            static_cast<std::uint16_t>(regs::ErrorDetail::kDeviceGone));
  EXPECT_TRUE(status->bit(regs::kDiError));
  const v1::InspectionReport scan_failed = report(1);
  ASSERT_GE(scan_failed.verdict().reasons_size(), 1);
  EXPECT_NE(scan_failed.verdict().reasons(0).find("scan failed"), std::string::npos);
  wait_online(*client, false);  // the daemon saw the device leave (hotplug)
  ASSERT_TRUE(client->acknowledge().ok());

  // The cable goes back in (a healthy device, as after a power cycle); the daemon reopens it.
  emulator_->set_faults({});
  emulator_->plug();
  wait_online(*client);
  auto refused = client->trigger(2, 1);  // ERROR is still latched
  ASSERT_TRUE(refused.ok()) << refused.message();
  EXPECT_FALSE(refused->accepted);
  EXPECT_EQ(refused->reject_code, regs::RejectCode::kErrorActive);
  ASSERT_TRUE(client->reset_errors().ok());
  auto next = client->run_cycle(3, 1);
  ASSERT_TRUE(next.ok()) << next.message();
  EXPECT_EQ(next->result.seq, 2);
  EXPECT_EQ(next->result.job_id, 3);
  EXPECT_EQ(next->result.code, regs::ResultCode::kOk);
  expect_springback(report(2), testing::kGoodSpringback, 0.05);
  EXPECT_EQ(daemon->stop(SIGTERM), 0);
}

// Found by the fault campaign (station_soak --faults): between scans nobody handled libusb's
// events, so the daemon never saw a scanner leave while it was idle. SCANNER_ONLINE stayed 1
// with the cable out, and a scanner power-cycled between two parts failed the next part's scan
// with ERROR_DETAIL 1 (device gone) although it was plugged in again.
TEST_F(HilTest, UnplugBetweenScansTurnsScannerOnlineOffAndReplugOn) {
  emulate(testing::kGoodSpringback);
  auto daemon = start_daemon();
  auto client = plc(daemon->port());
  wait_online(*client);
  emulator_->unplug();
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(5);
  auto offline = client->wait_for(
      [deadline](const auto& s) {
        return !s.bit(regs::kDiScannerOnline) || std::chrono::steady_clock::now() > deadline;
      },
      "SCANNER_ONLINE = 0");
  ASSERT_TRUE(offline.ok()) << offline.message();
  EXPECT_FALSE(offline->bit(regs::kDiScannerOnline)) << "5 s after the unplug";
  EXPECT_FALSE(offline->bit(regs::kDiReady));
  emulator_->plug();
  wait_online(*client);
  auto next = client->run_cycle(1, 1);
  ASSERT_TRUE(next.ok()) << next.message();
  EXPECT_EQ(next->result.code, regs::ResultCode::kOk);
}

TEST_F(HilTest, ScannerPowerCycledBetweenScansDoesNotFailTheNextScan) {
  emulate(testing::kGoodSpringback);
  auto daemon = start_daemon();
  auto client = plc(daemon->port());
  wait_online(*client);
  auto first = client->run_cycle(1, 1);
  ASSERT_TRUE(first.ok()) << first.message();
  EXPECT_EQ(first->result.code, regs::ResultCode::kOk);
  // Out and back in quicker than the runner's probe (1 s): the old handle is stale.
  emulator_->unplug();
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  emulator_->plug();
  auto next = client->run_cycle(2, 1);
  ASSERT_TRUE(next.ok()) << next.message();
  EXPECT_EQ(next->result.code, regs::ResultCode::kOk)
      << "ERROR_DETAIL " << client->read_status()->live[regs::kIrErrorDetail];
  EXPECT_EQ(next->error_code, 0);
}

TEST_F(HilTest, TriggerWhileBusyIsRejectedAndTheRunningCycleStillEndsOnce) {
  testing::HilDevice device;
  device.scan_duration_s = 1.0;
  emulate(testing::kGoodSpringback, device);
  auto daemon = start_daemon();
  auto client = plc(daemon->port());
  wait_online(*client);
  const auto start = std::chrono::steady_clock::now();
  auto first = client->trigger(7, 1);
  ASSERT_TRUE(first.ok() && first->accepted);
  ASSERT_TRUE(
      client->wait_for([](const auto& s) { return !s.bit(regs::kDiTriggerAck); }, "TRIG_ACK = 0")
          .ok());
  auto status = client->read_status();
  ASSERT_TRUE(status.ok());
  ASSERT_TRUE(status->bit(regs::kDiBusy)) << "the 1 s scan ended before the second trigger";
  auto second = client->trigger(8, 1);  // answered in the registers, never by an exception
  ASSERT_TRUE(second.ok()) << second.message();
  EXPECT_FALSE(second->accepted);
  EXPECT_EQ(second->reject_code, regs::RejectCode::kBusy);
  auto done = client->wait_result(*first, start);
  ASSERT_TRUE(done.ok()) << done.message();
  EXPECT_EQ(done->result.seq, 1);
  EXPECT_EQ(done->result.job_id, 7);  // the accepted trigger's job, not the refused one's
  EXPECT_EQ(done->result.code, regs::ResultCode::kOk);
  ASSERT_TRUE(client->acknowledge().ok());
  EXPECT_EQ(record_count(), 1);
  EXPECT_EQ(client->read_status()->live[regs::kIrTriggerCount], 1);
}

TEST_F(HilTest, PlcReconnectingMidHandshakeLosesAndDuplicatesNoResult) {
  testing::HilDevice device;
  device.scan_duration_s = 0.8;
  emulate(testing::kGoodSpringback, device);
  auto daemon = start_daemon();
  {
    auto client = plc(daemon->port());
    wait_online(*client);
    auto triggered = client->trigger(31, 1);
    ASSERT_TRUE(triggered.ok() && triggered->accepted);
  }  // the PLC's connection drops while the station is busy
  {
    auto client = plc(daemon->port());  // it comes back and waits for the result
    auto valid =
        client->wait_for([](const auto& s) { return s.bit(regs::kDiResultValid); }, "RESULT_VALID");
    ASSERT_TRUE(valid.ok()) << valid.message();
    auto read = client->read_result();
    ASSERT_TRUE(read.ok());
    EXPECT_EQ(read->seq, 1);
    EXPECT_EQ(read->job_id, 31);
  }  // and drops again before acknowledging
  auto client = plc(daemon->port());
  auto status = client->read_status();
  ASSERT_TRUE(status.ok());
  EXPECT_TRUE(status->bit(regs::kDiResultValid));  // still there: not lost
  auto read = client->read_result();
  ASSERT_TRUE(read.ok());
  EXPECT_EQ(read->seq, 1);
  ASSERT_TRUE(client->acknowledge().ok());
  auto next = client->run_cycle(32, 1);
  ASSERT_TRUE(next.ok()) << next.message();
  EXPECT_EQ(next->result.seq, 2);  // one new result per accepted trigger: none duplicated
  EXPECT_EQ(next->result.job_id, 32);
  EXPECT_EQ(record_count(), 2);
  EXPECT_EQ(report(1).job_id(), 31);
  EXPECT_EQ(report(2).job_id(), 32);
}

TEST_F(HilTest, KillDuringAnalysisLeavesNoHalfReportAndHonestRegistersAfterRestart) {
  emulate(testing::kGoodSpringback);
  std::uint16_t first_boot = 0;
  {
    auto daemon = start_daemon();
    auto client = plc(daemon->port());
    wait_online(*client);
    first_boot = client->read_status()->live[regs::kIrBootId];
    auto stored = client->run_cycle(10, 1);  // one complete result before the crash
    ASSERT_TRUE(stored.ok()) << stored.message();
    ASSERT_EQ(stored->result.seq, 1);
    auto triggered = client->trigger(11, 1);
    ASSERT_TRUE(triggered.ok() && triggered->accepted);
    ASSERT_TRUE(client
                    ->wait_for(
                        [](const auto& s) {
                          return state_is(s, regs::State::kAnalyzing) ||
                                 s.bit(regs::kDiResultValid);
                        },
                        "ANALYZING")
                    .ok());
    EXPECT_EQ(WTERMSIG(daemon->stop(SIGKILL)), SIGKILL);
  }
  // Every record is complete; a kill before the rename leaves only a hidden temporary.
  const int records = record_count();
  ASSERT_TRUE(records == 1 || records == 2) << records;
  for (int k = 1; k <= records; ++k) EXPECT_TRUE(report(k).has_verdict()) << "record " << k;

  auto daemon = start_daemon();
  for (const auto& name : report_dir_entries())
    EXPECT_NE(name.rfind(".tmp", 0), 0u) << name << " left over after the restart";
  auto client = plc(daemon->port());
  auto status = client->read_status();
  ASSERT_TRUE(status.ok());
  EXPECT_NE(status->live[regs::kIrBootId], first_boot);
  EXPECT_FALSE(status->bit(regs::kDiResultValid));  // nothing new since this boot
  EXPECT_FALSE(status->bit(regs::kDiBusy));
  auto shown = client->read_result();  // the last stored result, for reference
  ASSERT_TRUE(shown.ok());
  EXPECT_EQ(shown->seq, records);
  EXPECT_EQ(shown->job_id, records == 1 ? 10 : 11);
  wait_online(*client);  // the restarted daemon reopens the scanner the killed one had open
  auto next = client->run_cycle(12, 1);
  ASSERT_TRUE(next.ok()) << next.message();
  EXPECT_EQ(next->result.seq, records + 1);
  EXPECT_EQ(next->result.job_id, 12);
  EXPECT_EQ(next->result.code, regs::ResultCode::kOk);
}

TEST_F(HilTest, SigtermWhileTheScanWaitsOnASilentDeviceStopsPromptly) {
  testing::HilConfig config;
  config.scan_timeout_s = 600.0;  // the scan alone would wait ten minutes
  write_config(config);
  testing::HilDevice device;
  device.faults.stall_at_fraction = 0.3;  // the device stops sending mid-scan
  emulate(testing::kGoodSpringback, device);
  auto daemon = start_daemon();
  auto client = plc(daemon->port());
  wait_online(*client);
  auto triggered = client->trigger(1, 1);
  ASSERT_TRUE(triggered.ok() && triggered->accepted);
  ASSERT_TRUE(client
                  ->wait_for(
                      [](const auto& s) {
                        return state_is(s, regs::State::kAcquiring) &&
                               s.live[regs::kIrScanProgress] >= 30;
                      },
                      "the scan to stall at 30 %")
                  .ok());
  // stop() escalates to SIGKILL after 10 s (as systemd after TimeoutStopSec); a clean exit
  // status 0 means the daemon cancelled the scan and shut down by itself.
  const int status = daemon->stop(SIGTERM);
  EXPECT_TRUE(WIFEXITED(status)) << "killed by signal " << WTERMSIG(status);
  EXPECT_EQ(WEXITSTATUS(status), 0);
  // The interrupted inspection is on record as a cancelled scan, not as a result.
  const v1::InspectionReport cancelled = report(1);
  EXPECT_EQ(cancelled.result_code(), static_cast<std::uint32_t>(regs::ResultCode::kScanFailed));
  ASSERT_GE(cancelled.verdict().reasons_size(), 1);
  EXPECT_NE(cancelled.verdict().reasons(0).find("cancelled"), std::string::npos)
      << cancelled.verdict().reasons(0);
}

// A device fault, injected by the emulated scanner, and the ERROR_DETAIL the PLC must read.
struct FaultCase {
  const char* name;
  simulators::DeviceFaults faults;
  regs::ErrorDetail detail;
};
// Names the case in test output (gtest would print the struct's bytes).
void PrintTo(const FaultCase& c, std::ostream* os) { *os << c.name; }

simulators::DeviceFaults stuck_halt() {
  simulators::DeviceFaults f;
  f.halt_at_fraction = 0.4;
  f.halt_sticks = true;
  return f;
}
simulators::DeviceFaults skipped_profile() {
  simulators::DeviceFaults f;
  f.skip_frame_at_fraction = 0.5;
  return f;
}
simulators::DeviceFaults bad_crc() {
  simulators::DeviceFaults f;
  f.corrupt_crc_at_fraction = 0.5;
  return f;
}

class HilFaultDetail : public HilTest, public ::testing::WithParamInterface<FaultCase> {};

TEST_P(HilFaultDetail, DeviceFaultReachesThePlcAsItsErrorDetail) {
  testing::HilDevice device;
  device.faults = GetParam().faults;
  emulate(testing::kGoodSpringback, device);
  auto daemon = start_daemon();
  auto client = plc(daemon->port());
  wait_online(*client);
  auto failed = client->run_cycle(1, 1, false);
  ASSERT_TRUE(failed.ok()) << failed.message();
  EXPECT_EQ(failed->result.code, regs::ResultCode::kScanFailed);
  EXPECT_EQ(failed->error_code, static_cast<std::uint16_t>(regs::ErrorCode::kScanFailed));
  auto status = client->read_status();
  ASSERT_TRUE(status.ok());
  EXPECT_EQ(status->live[regs::kIrErrorDetail], static_cast<std::uint16_t>(GetParam().detail))
      << report(1).verdict().DebugString();
  EXPECT_EQ(daemon->stop(SIGTERM), 0);
}

INSTANTIATE_TEST_SUITE_P(
    Faults, HilFaultDetail,
    ::testing::Values(FaultCase{"StuckHalt", stuck_halt(), regs::ErrorDetail::kStalledEndpoint},
                      FaultCase{"SkippedProfile", skipped_profile(),
                                regs::ErrorDetail::kSequenceGap},
                      FaultCase{"BadCrc", bad_crc(), regs::ErrorDetail::kCorruptData}),
    [](const ::testing::TestParamInfo<FaultCase>& p) { return std::string(p.param.name); });

}  // namespace
}  // namespace springscan::daemon
