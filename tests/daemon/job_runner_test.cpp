#include "daemon/job_runner.hpp"

#include <gtest/gtest.h>
#include <poll.h>

#include <filesystem>

#include "test_rig.hpp"

namespace springscan::daemon {
namespace {

using testing::PlaneScanner;
using testing::TempDir;

class RunnerTest : public ::testing::Test {
 protected:
  RunnerTest()
      : dir_("springscan-runner"),
        store_(std::move(ReportStore::open({dir_.str(), 100}).value())),
        log_(LogLevel::kError, nullptr, false),
        runner_(
            scanner_,
            [this](std::uint16_t part, const analysis::PointCloud& scan) {
              last_part_ = part;
              return testing::plane_analysis(scan, 0.1);
            },
            store_, log_, RunnerSettings{"test-station", 0.05}) {}

  /// Starts a job and waits (poll on wake_fd) until it finished; returns the kFinished event.
  RunnerEvent run_job(std::uint64_t record, std::uint16_t part) {
    runner_.start(RunnerJob{record, JobRequest{100, part, Clock::now()}});
    for (int i = 0; i < 1000; ++i) {
      pollfd fd{runner_.wake_fd(), POLLIN, 0};
      poll(&fd, 1, 100);
      for (RunnerEvent& e : runner_.take_events()) {
        if (e.kind == RunnerEvent::Kind::kFinished) return e;
        acquired_ = true;
      }
    }
    ADD_FAILURE() << "the job did not finish";
    return {};
  }

  TempDir dir_;
  ReportStore store_;
  Log log_;
  PlaneScanner scanner_;
  std::uint16_t last_part_ = 0;
  bool acquired_ = false;
  JobRunner runner_;
};

TEST_F(RunnerTest, GoodPartIsPersistedBeforeItIsReported) {
  scanner_.offset_mm = 0.05;
  const RunnerEvent e = run_job(1, 3);
  EXPECT_TRUE(acquired_);
  EXPECT_EQ(last_part_, 3);
  EXPECT_TRUE(e.end.persisted);
  EXPECT_EQ(e.end.result_code, regs::ResultCode::kOk);
  EXPECT_TRUE(e.end.part_ok);
  EXPECT_EQ(e.end.error_code, regs::ErrorCode::kNone);
  EXPECT_TRUE(std::filesystem::exists(e.report_path + "/report.pb"));
  EXPECT_TRUE(std::filesystem::exists(e.report_path + "/deviation.ply"));
  EXPECT_EQ(e.block.seq, 1);
  EXPECT_EQ(e.block.part_id, 3);
  EXPECT_EQ(e.block.job_id, 100);
  EXPECT_EQ(regs::mm_to_um(e.block.max_deviation_mm), 50);  // the 0.05 mm the scanner lifted
  EXPECT_EQ(e.block.vectors.size(), 20u);                   // 2000 points, one per 100
  EXPECT_EQ(regs::mm_to_um(e.block.vectors[0].dz_mm), -50);
  auto latest = store_.load_latest();
  EXPECT_EQ((*latest)->station(), "test-station");
  EXPECT_EQ((*latest)->input().part_id(), "3");
  EXPECT_GE((*latest)->cycle_time_ms(), 0.0);
}

TEST_F(RunnerTest, PartOutOfToleranceFailsWithReasons) {
  scanner_.offset_mm = 0.25;
  const RunnerEvent e = run_job(1, 3);
  EXPECT_TRUE(e.end.persisted);
  EXPECT_EQ(e.end.result_code, regs::ResultCode::kFormNok);
  EXPECT_FALSE(e.end.part_ok);
  EXPECT_EQ(e.end.error_code, regs::ErrorCode::kNone);  // a bad part is not a station fault
  auto latest = store_.load_latest();
  ASSERT_EQ((*latest)->verdict().reasons_size(), 1);
  EXPECT_NE((*latest)->verdict().reasons(0).find("exceeds tolerance"), std::string::npos);
  EXPECT_EQ(regs::mm_to_um(e.block.max_deviation_mm), 250);
}

TEST_F(RunnerTest, UnplugDuringScanIsAFaultWithAStoredReasonThenNextJobPasses) {
  scanner_.unplug_next_scan = true;
  const RunnerEvent e = run_job(1, 3);
  EXPECT_TRUE(e.end.persisted);
  EXPECT_EQ(e.end.result_code, regs::ResultCode::kScanFailed);
  EXPECT_EQ(e.end.error_code, regs::ErrorCode::kScanFailed);
  EXPECT_EQ(e.end.error_detail, regs::ErrorDetail::kDeviceGone);
  EXPECT_FALSE(runner_.scanner_online());
  EXPECT_EQ(regs::mm_to_um(e.block.max_deviation_mm), regs::kInvalidInt32);
  auto latest = store_.load_latest();
  EXPECT_NE((*latest)->verdict().reasons(0).find("unplugged"), std::string::npos);
  // Replugged: the idle probe sees it again, the next job passes.
  scanner_.present = true;
  for (int i = 0; i < 200 && !runner_.scanner_online(); ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  EXPECT_TRUE(runner_.scanner_online());
  const RunnerEvent next = run_job(2, 3);
  EXPECT_EQ(next.end.result_code, regs::ResultCode::kOk);
  EXPECT_EQ(next.block.seq, 2);
}

TEST_F(RunnerTest, UnwritableReportDirectoryMeansNoValidResult) {
  std::filesystem::remove_all(dir_.str());  // the store's directory vanished (disk unmounted)
  const RunnerEvent e = run_job(1, 3);
  EXPECT_FALSE(e.end.persisted);
  EXPECT_EQ(e.end.error_code, regs::ErrorCode::kReportWriteFailed);
}

TEST(ScanErrorClassification, MapsMessagesToDetails) {
  EXPECT_EQ(classify_scan_error("LIBUSB_ERROR_NO_DEVICE: device gone"),
            regs::ErrorDetail::kDeviceGone);
  EXPECT_EQ(classify_scan_error("bulk transfer timed out"), regs::ErrorDetail::kTimeout);
  EXPECT_EQ(classify_scan_error("frame CRC mismatch"), regs::ErrorDetail::kCorruptData);
  EXPECT_EQ(classify_scan_error("scan cancelled"), regs::ErrorDetail::kCancelled);
  EXPECT_EQ(classify_scan_error("something else"), regs::ErrorDetail::kOther);
}

}  // namespace
}  // namespace springscan::daemon
