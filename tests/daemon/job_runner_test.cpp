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
            [this](std::uint16_t part, const analysis::PointCloud& scan)
                -> analysis::Expected<analysis::InspectionOutcome> {
              last_part_ = part;
              if (fail_analysis_) return *fail_analysis_;
              auto outcome = testing::plane_analysis(scan, 0.1, uncertainty_mm_);
              if (outcome && !lost_datum_.empty()) lose_datum(outcome->report);
              return outcome;
            },
            store_, log_, RunnerSettings{"test-station", 0.05, {}}) {}

  /// What the pipeline reports when a datum cannot be measured (pipeline.cpp, result_frame):
  /// the alignment not achieved with the datum named, the verdict FAIL.
  void lose_datum(v1::InspectionReport& report) const {
    v1::Alignment& a = *report.mutable_alignment();
    a.set_method("best_fit");
    a.set_achieved(false);
    a.set_failed_datum(lost_datum_);
    a.set_failure("datum '" + lost_datum_ + "' (hole) cannot be measured: 0 scan points");
    report.mutable_verdict()->set_pass(false);
    report.mutable_verdict()->set_decision(v1::Verdict::FAIL);
    report.mutable_verdict()->add_reasons("alignment: " + a.failure());
  }

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
  std::optional<analysis::Error> fail_analysis_;  // set before run_job
  bool acquired_ = false;
  double uncertainty_mm_ = 0.0;  // the fake analysis's U of max |d|
  std::string lost_datum_;       // set: the fake analysis could not measure this datum
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

// Within U of the tolerance: RESULT_CODE 6 UNDECIDED, not PART_OK, not a station fault; the
// report keeps its decision.
TEST_F(RunnerTest, PartWithinUOfItsToleranceIsUndecided) {
  scanner_.offset_mm = 0.12;
  uncertainty_mm_ = 0.05;
  const RunnerEvent e = run_job(1, 3);
  EXPECT_TRUE(e.end.persisted);
  EXPECT_EQ(e.end.result_code, regs::ResultCode::kUndecided);
  EXPECT_FALSE(e.end.part_ok);
  EXPECT_EQ(e.end.error_code, regs::ErrorCode::kNone);
  EXPECT_EQ(e.block.code, regs::ResultCode::kUndecided);
  auto latest = store_.load_latest();
  EXPECT_EQ((*latest)->result_code(), 6u);
  EXPECT_FALSE((*latest)->verdict().pass());
  EXPECT_EQ((*latest)->verdict().decision(), v1::Verdict::UNDECIDED);
  // Beyond by more than U: FAIL as before.
  scanner_.offset_mm = 0.2;
  EXPECT_EQ(run_job(2, 3).end.result_code, regs::ResultCode::kFormNok);
}

// A datum not measurable: the result is stored and announced as the verdict made it (NOK, in
// the best-fit frame), and the PLC gets ERROR_CODE 3 with ERROR_DETAIL 10 (a FAULT) beside it.
TEST_F(RunnerTest, DatumNotMeasurableIsANokResultWithItsErrorDetail) {
  scanner_.offset_mm = 0.05;  // within tolerance: the datum alone makes the part NOK
  lost_datum_ = "B";
  const RunnerEvent e = run_job(1, 3);
  EXPECT_TRUE(e.end.persisted);
  EXPECT_EQ(e.end.result_code, regs::ResultCode::kFormNok);
  EXPECT_FALSE(e.end.part_ok);
  EXPECT_EQ(e.end.error_code, regs::ErrorCode::kAnalysisFailed);
  EXPECT_EQ(e.end.error_detail, regs::ErrorDetail::kDatumNotMeasurable);
  EXPECT_EQ(static_cast<int>(e.end.error_detail), 10);  // the register map's number
  auto latest = store_.load_latest();
  EXPECT_EQ((*latest)->alignment().failed_datum(), "B");
  EXPECT_FALSE((*latest)->verdict().pass());
  // The station's registers: a valid NOK result, and the fault with its detail.
  InspectionMachine machine(MachineSettings{}, Clock::now());
  machine.on_job_finished(e.end, Clock::now());
  EXPECT_TRUE(machine.status().result_valid);
  EXPECT_FALSE(machine.status().part_ok);
  EXPECT_EQ(machine.status().error_code, regs::ErrorCode::kAnalysisFailed);
  EXPECT_EQ(machine.status().error_detail, regs::ErrorDetail::kDatumNotMeasurable);
  // Measurable again: no error beside the next result.
  lost_datum_.clear();
  const RunnerEvent next = run_job(2, 3);
  EXPECT_EQ(next.end.result_code, regs::ResultCode::kOk);
  EXPECT_EQ(next.end.error_code, regs::ErrorCode::kNone);
}

TEST(PlcErrorMapping, OnlyANamedDatumNotMeasuredIsAnError) {
  v1::Alignment a;
  EXPECT_FALSE(plc_error_for_alignment(a));  // no alignment section (a report before datums)
  a.set_achieved(true);
  EXPECT_FALSE(plc_error_for_alignment(a));
  a.set_achieved(false);
  a.set_failed_datum("A2");
  const auto e = plc_error_for_alignment(a);
  ASSERT_TRUE(e);
  EXPECT_EQ(*e,
            (PlcError{regs::ErrorCode::kAnalysisFailed, regs::ErrorDetail::kDatumNotMeasurable}));
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

TEST_F(RunnerTest, ScanFailureCodeReachesThePlcAsErrorDetail) {
  // The message says nothing the old text search knew: only the code decides.
  scanner_.fail_next_scan =
      analysis::fail(analysis::ErrorCode::kStalledEndpoint, "scanner SN-1: clear halt on 0x81");
  const RunnerEvent e = run_job(1, 3);
  EXPECT_TRUE(e.end.persisted);
  EXPECT_EQ(e.end.result_code, regs::ResultCode::kScanFailed);
  EXPECT_EQ(e.end.error_code, regs::ErrorCode::kScanFailed);
  EXPECT_EQ(e.end.error_detail, regs::ErrorDetail::kStalledEndpoint);
}

TEST_F(RunnerTest, PartModelFailureIsErrorCode4ByItsCode) {
  fail_analysis_ = analysis::fail(analysis::ErrorCode::kNotFound, "hat.step: no such file");
  const RunnerEvent e = run_job(1, 3);
  EXPECT_TRUE(e.end.persisted);
  EXPECT_EQ(e.end.result_code, regs::ResultCode::kAnalysisFailed);
  EXPECT_EQ(e.end.error_code, regs::ErrorCode::kPartModelFailed);
  fail_analysis_ = analysis::fail(analysis::ErrorCode::kAnalysisFailed, "3 points, at least 10");
  EXPECT_EQ(run_job(2, 3).end.error_code, regs::ErrorCode::kAnalysisFailed);
}

// The PLC's ERROR_CODE / ERROR_DETAIL for every error code, as docs/modbus-register-map.md
// ("Error codes") lists them.
struct CodeRow {
  analysis::ErrorCode code;
  PlcError scan;      // when Scanner::scan fails with `code`
  PlcError analysis;  // when the AnalyzeFn fails with `code`
};

TEST(PlcErrorMapping, EveryCodeHasItsRegisterValues) {
  using analysis::ErrorCode;
  using D = regs::ErrorDetail;
  using E = regs::ErrorCode;
  const CodeRow rows[] = {
      {ErrorCode::kInvalidInput, {E::kScanFailed, D::kOther}, {E::kAnalysisFailed, D::kOther}},
      {ErrorCode::kNotFound, {E::kScanFailed, D::kDeviceGone}, {E::kPartModelFailed, D::kOther}},
      {ErrorCode::kIoError, {E::kScanFailed, D::kOther}, {E::kPartModelFailed, D::kOther}},
      {ErrorCode::kCorruption, {E::kScanFailed, D::kOther}, {E::kPartModelFailed, D::kOther}},
      {ErrorCode::kInvalidSettings, {E::kScanFailed, D::kOther}, {E::kPartModelFailed, D::kOther}},
      {ErrorCode::kAnalysisFailed, {E::kScanFailed, D::kOther}, {E::kAnalysisFailed, D::kOther}},
      {ErrorCode::kCancelled, {E::kScanFailed, D::kCancelled}, {E::kAnalysisFailed, D::kCancelled}},
      {ErrorCode::kDeviceGone, {E::kScanFailed, D::kDeviceGone}, {E::kAnalysisFailed, D::kOther}},
      {ErrorCode::kTimeout, {E::kScanFailed, D::kTimeout}, {E::kAnalysisFailed, D::kOther}},
      {ErrorCode::kStalledEndpoint,
       {E::kScanFailed, D::kStalledEndpoint},
       {E::kAnalysisFailed, D::kOther}},
      {ErrorCode::kBadCrc, {E::kScanFailed, D::kCorruptData}, {E::kAnalysisFailed, D::kOther}},
      {ErrorCode::kSequenceGap, {E::kScanFailed, D::kSequenceGap}, {E::kAnalysisFailed, D::kOther}},
      {ErrorCode::kProtocolError,
       {E::kScanFailed, D::kProtocolError},
       {E::kAnalysisFailed, D::kOther}},
      {ErrorCode::kDeviceFault, {E::kScanFailed, D::kDeviceFault}, {E::kAnalysisFailed, D::kOther}},
      {ErrorCode::kOsError, {E::kScanFailed, D::kOther}, {E::kAnalysisFailed, D::kOther}},
      {ErrorCode::kInternal, {E::kInternal, D::kOther}, {E::kInternal, D::kOther}},
  };
  for (const CodeRow& row : rows) {
    const std::string name = analysis::to_string(row.code);
    EXPECT_EQ(plc_error_for_scan(row.code), row.scan) << name;
    EXPECT_EQ(plc_error_for_analysis(row.code), row.analysis) << name;
    EXPECT_NE(name, "unknown error");
  }
  // The detail values are the register map's numbers (the PLC programs against them).
  EXPECT_EQ(static_cast<int>(D::kStalledEndpoint), 5);
  EXPECT_EQ(static_cast<int>(D::kSequenceGap), 6);
  EXPECT_EQ(static_cast<int>(D::kProtocolError), 7);
  EXPECT_EQ(static_cast<int>(D::kDeviceFault), 8);
}

}  // namespace
}  // namespace springscan::daemon
