// Hardware-in-the-loop: the real springscand process, the scanner simulator presented as a USB
// device through umockdev (the daemon runs with the umockdev preload, so its production libusb
// path talks to the emulated device), the real analysis pipeline on the part's CAD file, and
// the simulated PLC (plus mbpoll) over loopback TCP.
#include <gtest/gtest.h>

#include <csignal>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>

#include "analysis/cad_profile.hpp"
#include "analysis/sheet_part.hpp"
#include "daemon_process.hpp"
#include "simulators/plc_client.hpp"
#include "simulators/usb_emulator.hpp"
#include "test_rig.hpp"

namespace springscan::daemon {
namespace {

namespace fs = std::filesystem;
using simulators::EmulatedUsbScanner;
using simulators::PlcClient;
using testing::DaemonProcess;
using testing::TempDir;

const analysis::ProfileSpec& nominal() {
  static const analysis::ProfileSpec spec = analysis::l_profile(60, 25, 90, 3);
  return spec;
}

/// A dense, noise-free surface of the part as produced with `springback_deg` at its bend.
analysis::PointCloud surface(double springback_deg) {
  analysis::ScanSimulationSettings dense;
  dense.point_count = 60000;
  dense.noise_sigma_mm = 0.0;
  return *analysis::simulate_scan(nominal(), {springback_deg}, dense);
}

simulators::ScannerDeviceSettings device() {
  simulators::ScannerDeviceSettings s;
  s.noise.sigma_mm = 0.02;
  s.laser.step_mm = 2.0;
  s.laser.points_per_profile = 128;
  return s;
}

class HilTest : public ::testing::Test {
 protected:
  HilTest() : dir_("springscan-hil") {
    // The emulator answers the child's ioctls over a socket; a child that dies (kill -9)
    // must not take the test process down with SIGPIPE.
    std::signal(SIGPIPE, SIG_IGN);
    const std::string cad = dir_.str() + "/l-bracket.step";
    if (!analysis::write_profile_cad(nominal(), cad).ok()) throw std::runtime_error("CAD");
    std::ofstream(config_path()) << "modbus { bind_address: \"127.0.0.1\" port: 0\n"
                                    "  allowed_clients: \"127.0.0.1\" }\n"
                                    "scanner { kind: LASER_LINE timeout_s: 1 }\n"
                                    "parts { part_id: 1 name: \"L-bracket\" cad_file: \""
                                 << cad
                                 << "\" settings { verdict { tolerance_mm: 0.1 } } }\n"
                                    "report_dir: \"reports\"\nlog_level: \"warning\"\n";
  }
  std::string config_path() const { return dir_.str() + "/station.textproto"; }
  /// The verdict part of record `record`'s report.json, for failure messages.
  std::string report_text(int record) const {
    char name[32];
    std::snprintf(name, sizeof name, "/r%012d/report.json", record);
    std::ifstream json(reports() + name);
    const std::string text((std::istreambuf_iterator<char>(json)), {});
    const auto at = text.find("\"verdict\"");
    return at == std::string::npos ? text.substr(0, 2000) : text.substr(at, 1500);
  }
  std::string reports() const { return dir_.str() + "/reports"; }

  void emulate(double springback_deg) {
    auto emulator = EmulatedUsbScanner::create(device(), surface(springback_deg));
    ASSERT_TRUE(emulator.ok()) << emulator.message();
    emulator_ = std::move(*emulator);
  }
  std::unique_ptr<DaemonProcess> start_daemon() const {
    return std::make_unique<DaemonProcess>(
        SPRINGSCAND_EXE, config_path(), dir_.str(),
        std::vector<std::string>{"LD_PRELOAD=" + simulators::umockdev_preload_library(),
                                 "UMOCKDEV_DIR=" + emulator_->root_dir()});
  }
  /// RESULT_CODE must say what the stored report's verdict says (OK iff verdict.pass).
  void expect_code_matches_report(regs::ResultCode code, int record) const {
    char name[32];
    std::snprintf(name, sizeof name, "/r%012d/report.pb", record);
    std::ifstream in(reports() + name, std::ios::binary);
    v1::InspectionReport report;
    ASSERT_TRUE(report.ParseFromIstream(&in));
    EXPECT_EQ(code, report.verdict().pass() ? regs::ResultCode::kOk : regs::ResultCode::kFormNok);
    EXPECT_EQ(report.result_code(), static_cast<std::uint32_t>(code));
  }
  static std::unique_ptr<PlcClient> plc(int port) {
    simulators::PlcClientSettings settings;
    settings.port = port;
    settings.step_timeout_s = 120.0;  // the sanitizer build analyses slowly
    auto client = PlcClient::connect(settings);
    if (!client) throw std::runtime_error(client.message());
    return std::move(*client);
  }
  static void wait_online(PlcClient& plc) {
    ASSERT_TRUE(plc.wait_for([](const auto& s) { return s.bit(regs::kDiScannerOnline); },
                             "SCANNER_ONLINE").ok());
  }

  TempDir dir_;
  std::unique_ptr<EmulatedUsbScanner> emulator_;
};

TEST_F(HilTest, GoodPartMeasuresWithinNoiseAndMbpollReadsTheResultBlock) {
  emulate(0.0);
  auto daemon = start_daemon();
  auto client = plc(daemon->port());
  wait_online(*client);
  auto cycle = client->run_cycle(21, 1, false);
  ASSERT_TRUE(cycle.ok()) << cycle.message();
  ASSERT_TRUE(cycle->accepted);
  EXPECT_EQ(cycle->result.seq, 1);
  EXPECT_EQ(cycle->result.job_id, 21);
  EXPECT_LT(cycle->result.max_deviation_um, 300) << report_text(1);  // noise 0.02 mm
  EXPECT_LT(cycle->result.rms_deviation_um, 60);
  EXPECT_EQ(cycle->result.code, regs::ResultCode::kOk) << report_text(1);
  EXPECT_TRUE(cycle->part_ok);
  expect_code_matches_report(cycle->result.code, 1);
  EXPECT_TRUE(fs::exists(reports() + "/r000000000001/report.json"));
  // A third-party client: Debian's mbpoll, 0-based addresses, FC04, one poll.
  const std::string command = "mbpoll -m tcp -a 1 -0 -1 -t 3 -r 100 -c 3 -p " +
                              std::to_string(daemon->port()) + " 127.0.0.1 2>&1";
  std::FILE* pipe = ::popen(command.c_str(), "r");
  ASSERT_NE(pipe, nullptr);
  std::string output;
  char line[256];
  while (std::fgets(line, sizeof line, pipe) != nullptr) output += line;
  EXPECT_EQ(::pclose(pipe), 0) << output;
  EXPECT_NE(output.find("[100]: \t1"), std::string::npos) << output;  // RESULT_SEQ
  EXPECT_NE(output.find("[102]: \t21"), std::string::npos) << output;  // JOB_ID echo
}

TEST_F(HilTest, SpringbackOutOfToleranceShowsInTheResultAndTheReport) {
  emulate(8.0);  // the 25 mm leg opens by 8 degrees: up to 3.5 mm at its end
  auto daemon = start_daemon();
  auto client = plc(daemon->port());
  wait_online(*client);
  auto cycle = client->run_cycle(1, 1);
  ASSERT_TRUE(cycle.ok()) << cycle.message();
  // The verdict itself is the pipeline's (checked by its own tests); here: the registers carry
  // the measured deviation and a RESULT_CODE that agrees with the stored report.
  EXPECT_EQ(cycle->part_ok, cycle->result.code == regs::ResultCode::kOk);
  EXPECT_GT(cycle->result.max_deviation_um, 500) << report_text(1);  // far beyond the noise
  expect_code_matches_report(cycle->result.code, 1);
}

TEST_F(HilTest, UnplugMidScanIsAFaultWithAStoredReport) {
  // The device disconnects halfway through the scan (replug and the next cycle are covered
  // in-process by StationTest: umockdev does not carry a replug over to a child process).
  emulate(0.0);
  emulator_->unplug();
  simulators::DeviceFaults faults;
  faults.unplug_at_fraction = 0.5;
  emulator_->set_faults(faults);
  emulator_->plug();
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
  EXPECT_EQ(status->live[regs::kIrState], static_cast<std::uint16_t>(regs::State::kFault));
  EXPECT_EQ(status->live[regs::kIrErrorDetail],
            static_cast<std::uint16_t>(regs::ErrorDetail::kDeviceGone));
  EXPECT_TRUE(status->bit(regs::kDiError));
  EXPECT_NE(report_text(1).find("scan failed"), std::string::npos) << report_text(1);
  daemon->stop(SIGKILL);  // its libusb may be blocked on the vanished emulated device
}

TEST_F(HilTest, KillDuringAnalysisLeavesNoHalfReportAndHonestRegisters) {
  emulate(0.0);
  std::uint16_t first_boot = 0;
  {
    auto daemon = start_daemon();
    auto client = plc(daemon->port());
    wait_online(*client);
    first_boot = client->read_status()->live[regs::kIrBootId];
    auto triggered = client->trigger(1, 1);
    ASSERT_TRUE(triggered.ok() && triggered->accepted);
    ASSERT_TRUE(client->wait_for([](const auto& s) {
                  return s.live[regs::kIrState] == static_cast<int>(regs::State::kAnalyzing) ||
                         s.bit(regs::kDiResultValid);
                }, "ANALYZING").ok());
    daemon->stop(SIGKILL);
  }
  for (const auto& entry : fs::directory_iterator(reports())) {
    const std::string name = entry.path().filename().string();
    if (name.rfind("r", 0) == 0) {  // a record, if the kill came late, is complete
      EXPECT_TRUE(fs::exists(entry.path() / "report.pb")) << name;
      EXPECT_TRUE(fs::exists(entry.path() / "report.json")) << name;
    }
  }
  auto daemon = start_daemon();
  auto client = plc(daemon->port());
  auto status = client->read_status();
  ASSERT_TRUE(status.ok());
  EXPECT_NE(status->live[regs::kIrBootId], first_boot);
  EXPECT_FALSE(status->bit(regs::kDiResultValid));
  EXPECT_FALSE(status->bit(regs::kDiBusy));
  for (const auto& entry : fs::directory_iterator(reports())) {
    EXPECT_NE(entry.path().filename().string().rfind(".tmp-", 0), 0u);  // cleaned at start
  }
  wait_online(*client);
  auto next = client->run_cycle(2, 1);
  ASSERT_TRUE(next.ok()) << next.message();
  EXPECT_EQ(next->result.job_id, 2);
}

}  // namespace
}  // namespace springscan::daemon
