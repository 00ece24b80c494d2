#include "daemon/state_machine.hpp"

#include <gtest/gtest.h>

#include <algorithm>

namespace springscan::daemon {
namespace {

using namespace std::chrono_literals;
using regs::RejectCode;
using regs::State;

bool has(const MachineStep& step, MachineEvent event) {
  return std::find(step.events.begin(), step.events.end(), event) != step.events.end();
}

// Drives the machine like the event loop does, with a controllable clock.
class MachineTest : public ::testing::Test {
 protected:
  explicit MachineTest(MachineSettings settings = {}) : machine_(settings, t_) {
    plc_.trigger_enable = true;
  }

  MachineStep update(Clock::duration advance = 10ms) {
    t_ += advance;
    return machine_.update(plc_, online_, t_);
  }
  /// Trigger edge with ids, then release; returns the accepted job (or fails the test).
  JobRequest trigger(std::uint16_t job, std::uint16_t part) {
    plc_.job_id = job;
    plc_.part_id = part;
    plc_.trigger = true;
    const MachineStep step = update();
    EXPECT_TRUE(step.start.has_value());
    plc_.trigger = false;
    update();
    return step.start.value_or(JobRequest{});
  }
  void finish(regs::ResultCode code, bool pass, regs::ErrorCode error = regs::ErrorCode::kNone) {
    machine_.on_job_finished(JobEnd{code, pass, true, error, regs::ErrorDetail::kNone}, t_);
    update();
  }
  void pulse(bool PlcControl::*coil) {
    plc_.*coil = true;
    update();
    plc_.*coil = false;
    update();
  }

  Clock::time_point t_ = Clock::time_point{} + 1h;
  InspectionMachine machine_;
  PlcControl plc_;
  bool online_ = true;
};

TEST_F(MachineTest, FullHandshakeGoodPart) {
  update();
  EXPECT_TRUE(machine_.status().ready);
  EXPECT_EQ(machine_.status().state, State::kIdle);
  plc_.job_id = 7;
  plc_.part_id = 3;
  plc_.part_serial = 4711;
  plc_.trigger = true;
  const MachineStep step = update();
  ASSERT_TRUE(step.start.has_value());
  EXPECT_EQ(step.start->job_id, 7);
  EXPECT_EQ(step.start->part_id, 3);
  EXPECT_EQ(step.start->part_serial, 4711u);  // latched with the ids
  EXPECT_TRUE(machine_.status().trigger_ack);
  EXPECT_TRUE(machine_.status().busy);
  EXPECT_FALSE(machine_.status().ready);
  EXPECT_EQ(machine_.status().state, State::kAcquiring);
  EXPECT_EQ(machine_.status().trigger_count, 1);
  plc_.trigger = false;
  update();
  EXPECT_FALSE(machine_.status().trigger_ack);  // dropped after the PLC dropped TRIGGER
  machine_.on_acquired();
  EXPECT_EQ(machine_.status().state, State::kAnalyzing);
  finish(regs::ResultCode::kOk, true);
  EXPECT_TRUE(machine_.status().result_valid);
  EXPECT_TRUE(machine_.status().part_ok);
  EXPECT_FALSE(machine_.status().busy);
  EXPECT_EQ(machine_.status().state, State::kDone);
  EXPECT_FALSE(machine_.status().ready);  // previous result not yet acknowledged
  pulse(&PlcControl::result_ack);
  EXPECT_FALSE(machine_.status().result_valid);
  EXPECT_FALSE(machine_.status().part_ok);
  EXPECT_TRUE(machine_.status().ready);
  EXPECT_EQ(machine_.status().state, State::kIdle);
}

TEST_F(MachineTest, TriggerWhileBusyIsRejectedWithCodeAndNothingQueued) {
  update();
  trigger(1, 1);
  plc_.trigger = true;
  const MachineStep step = update();
  EXPECT_FALSE(step.start.has_value());
  EXPECT_TRUE(has(step, MachineEvent::kTriggerRejected));
  EXPECT_TRUE(machine_.status().trigger_rejected);
  EXPECT_EQ(machine_.status().reject_code, RejectCode::kBusy);
  EXPECT_EQ(machine_.status().reject_count, 1);
  EXPECT_EQ(machine_.status().trigger_count, 1);
  EXPECT_FALSE(machine_.status().error());  // a rejection is not a fault
  plc_.trigger = false;
  update();
  finish(regs::ResultCode::kOk, true);
  // Nothing was queued: after the job, no second job starts by itself.
  EXPECT_FALSE(update().start.has_value());
  EXPECT_EQ(machine_.status().trigger_count, 1);
}

TEST_F(MachineTest, TriggerHighAtStartIsIgnoredUntilItDrops) {
  plc_.trigger = true;
  MachineStep step = update();
  EXPECT_FALSE(step.start.has_value());
  EXPECT_TRUE(has(step, MachineEvent::kTriggerHeldAtStart));
  step = update(1s);
  EXPECT_FALSE(step.start.has_value());
  EXPECT_FALSE(machine_.status().trigger_rejected);
  plc_.trigger = false;
  update();
  plc_.trigger = true;
  EXPECT_TRUE(update().start.has_value());
}

// An UNDECIDED result raises PART_UNDECIDED, never PART_OK (even if a runner said pass), and
// both drop with RESULT_ACK; the PLC's re-measure is an ordinary next trigger.
TEST_F(MachineTest, UndecidedResultIsNeverPartOkAndClearsWithTheAck) {
  update();
  trigger(1, 1);
  finish(regs::ResultCode::kUndecided, true);
  EXPECT_TRUE(machine_.status().result_valid);
  EXPECT_TRUE(machine_.status().part_undecided);
  EXPECT_FALSE(machine_.status().part_ok);
  pulse(&PlcControl::result_ack);
  EXPECT_FALSE(machine_.status().part_undecided);
  EXPECT_TRUE(machine_.status().ready);
  trigger(1, 1);  // the re-measure
  finish(regs::ResultCode::kOk, true);
  EXPECT_TRUE(machine_.status().part_ok);
  EXPECT_FALSE(machine_.status().part_undecided);
}

TEST_F(MachineTest, ResultNotAcknowledgedRejectsNextTrigger) {
  update();
  trigger(1, 1);
  finish(regs::ResultCode::kFormNok, false);
  EXPECT_FALSE(machine_.status().part_ok);
  plc_.trigger = true;
  EXPECT_FALSE(update().start.has_value());
  EXPECT_EQ(machine_.status().reject_code, RejectCode::kResultNotAcked);
  EXPECT_TRUE(machine_.status().result_valid);  // a rejected trigger does not clear the result
}

TEST(MachineAutoAck, AcceptedTriggerClearsResultValid) {
  MachineSettings settings;
  settings.auto_ack_on_trigger = true;
  const auto t0 = Clock::time_point{} + 1h;
  InspectionMachine machine(settings, t0);
  PlcControl plc;
  plc.trigger_enable = true;
  machine.update(plc, true, t0);
  plc.trigger = true;
  ASSERT_TRUE(machine.update(plc, true, t0 + 10ms).start);
  plc.trigger = false;
  machine.update(plc, true, t0 + 20ms);
  machine.on_job_finished(JobEnd{regs::ResultCode::kOk, true, true, {}, {}}, t0 + 30ms);
  machine.update(plc, true, t0 + 40ms);
  EXPECT_TRUE(machine.status().result_valid);
  EXPECT_TRUE(machine.status().ready);
  plc.trigger = true;
  ASSERT_TRUE(machine.update(plc, true, t0 + 50ms).start);
  EXPECT_FALSE(machine.status().result_valid);
}

TEST_F(MachineTest, NewTriggerWithNewJobClearsResultValid) {
  update();
  trigger(1, 1);
  finish(regs::ResultCode::kOk, true);
  ASSERT_TRUE(machine_.status().result_valid);
  // The PLC writes JOB_ID and TRIGGER in one request: the job change clears the old result.
  plc_.job_id = 2;
  plc_.trigger = true;
  const MachineStep step = update();
  EXPECT_TRUE(has(step, MachineEvent::kResultClearedByJobChange));
  EXPECT_TRUE(step.start.has_value());
  EXPECT_FALSE(machine_.status().result_valid);
}

TEST_F(MachineTest, JobIdWrittenByARefusedTriggerWhileBusyKeepsTheComingResult) {
  update();
  trigger(1, 1);
  plc_.job_id = 2;  // a second trigger while busy: refused, but JOB_ID was written
  plc_.trigger = true;
  EXPECT_FALSE(update().start.has_value());
  plc_.trigger = false;
  update();
  finish(regs::ResultCode::kOk, true);
  EXPECT_TRUE(machine_.status().result_valid);
}

TEST_F(MachineTest, ResultPastTtlStaysValidAndIsFlaggedStaleUntilAcknowledged) {
  update();
  trigger(1, 1);
  finish(regs::ResultCode::kOk, true);
  update(29s);
  EXPECT_TRUE(machine_.status().result_valid);
  EXPECT_FALSE(machine_.status().result_stale);
  const MachineStep step = update(2s);
  EXPECT_TRUE(has(step, MachineEvent::kResultStale));
  EXPECT_TRUE(machine_.status().result_valid);  // none lost: kept until acknowledged
  EXPECT_TRUE(machine_.status().part_ok);
  EXPECT_TRUE(machine_.status().result_stale);
  EXPECT_EQ(machine_.status().state, State::kDone);
  EXPECT_FALSE(machine_.status().ready);
  EXPECT_FALSE(has(update(1h), MachineEvent::kResultStale));  // said once
  EXPECT_TRUE(machine_.status().result_valid);
  pulse(&PlcControl::result_ack);
  EXPECT_FALSE(machine_.status().result_valid);
  EXPECT_FALSE(machine_.status().result_stale);
  EXPECT_TRUE(machine_.status().ready);
}

TEST(MachineAutoAck, IsOffByDefaultAndAStaleResultIsSupersededByTheNextTrigger) {
  EXPECT_FALSE(MachineSettings{}.auto_ack_on_trigger);
  MachineSettings settings;
  settings.auto_ack_on_trigger = true;
  auto t = Clock::time_point{} + 1h;
  InspectionMachine machine(settings, t);
  PlcControl plc;
  plc.trigger_enable = true;
  machine.update(plc, true, t);
  plc.trigger = true;
  ASSERT_TRUE(machine.update(plc, true, t += 10ms).start);
  plc.trigger = false;
  machine.update(plc, true, t += 10ms);
  machine.on_job_finished(JobEnd{regs::ResultCode::kOk, true, true, {}, {}}, t);
  machine.update(plc, true, t += 31s);
  EXPECT_TRUE(machine.status().result_stale);
  plc.trigger = true;
  ASSERT_TRUE(machine.update(plc, true, t += 10ms).start);
  EXPECT_FALSE(machine.status().result_valid);
  EXPECT_FALSE(machine.status().result_stale);
}

TEST_F(MachineTest, ErrorResetWithoutAnErrorKeepsTheResult) {
  update();
  trigger(1, 1);
  finish(regs::ResultCode::kFormNok, false);
  pulse(&PlcControl::error_reset);
  EXPECT_TRUE(machine_.status().result_valid);
  EXPECT_EQ(machine_.status().state, State::kDone);
  EXPECT_FALSE(machine_.status().ready);  // still to be acknowledged
  pulse(&PlcControl::result_ack);
  EXPECT_TRUE(machine_.status().ready);
  EXPECT_EQ(machine_.status().state, State::kIdle);
}

TEST_F(MachineTest, ScanFaultNeedsResetThenNextCyclePasses) {
  update();
  trigger(1, 1);
  finish(regs::ResultCode::kScanFailed, false, regs::ErrorCode::kScanFailed);
  EXPECT_EQ(machine_.status().state, State::kFault);
  EXPECT_TRUE(machine_.status().error());
  EXPECT_TRUE(machine_.status().result_valid);  // the failed cycle's result is published
  EXPECT_FALSE(machine_.status().part_ok);
  EXPECT_FALSE(machine_.status().ready);
  plc_.trigger = true;
  EXPECT_FALSE(update().start.has_value());
  EXPECT_EQ(machine_.status().reject_code, RejectCode::kErrorActive);
  plc_.trigger = false;
  update();
  pulse(&PlcControl::result_ack);  // acknowledging the failed result leaves the FAULT
  EXPECT_FALSE(machine_.status().result_valid);
  EXPECT_EQ(machine_.status().state, State::kFault);
  EXPECT_FALSE(machine_.status().ready);
  pulse(&PlcControl::error_reset);
  EXPECT_FALSE(machine_.status().error());
  EXPECT_FALSE(machine_.status().trigger_rejected);
  EXPECT_EQ(machine_.status().state, State::kIdle);
  EXPECT_TRUE(machine_.status().ready);
  trigger(2, 1);
  finish(regs::ResultCode::kOk, true);
  EXPECT_TRUE(machine_.status().part_ok);
}

TEST_F(MachineTest, UnpersistedResultIsNeverValid) {
  update();
  trigger(1, 1);
  machine_.on_job_finished(JobEnd{regs::ResultCode::kOk, true, false, {}, {}}, t_);
  update();
  EXPECT_FALSE(machine_.status().result_valid);
  EXPECT_EQ(machine_.status().error_code, regs::ErrorCode::kReportWriteFailed);
  EXPECT_EQ(machine_.status().state, State::kFault);
}

TEST_F(MachineTest, SilentPlcHeartbeatRaisesCommLostUntilResetWithLiveHeartbeat) {
  update();
  update(5s);  // no heartbeat yet: monitoring is not armed
  EXPECT_FALSE(machine_.status().plc_comm_lost);
  plc_.plc_heartbeat = 1;
  update();
  update(2900ms);
  EXPECT_FALSE(machine_.status().plc_comm_lost);
  const MachineStep step = update(200ms);
  EXPECT_TRUE(has(step, MachineEvent::kCommLost));
  EXPECT_TRUE(machine_.status().plc_comm_lost);
  EXPECT_FALSE(machine_.status().ready);
  EXPECT_TRUE(machine_.status().error());  // a PLC watching ERROR sees why READY dropped
  EXPECT_EQ(machine_.status().error_code, regs::ErrorCode::kPlcCommLost);
  EXPECT_EQ(machine_.status().state, State::kIdle);  // not a FAULT
  plc_.trigger = true;
  EXPECT_FALSE(update().start.has_value());
  EXPECT_EQ(machine_.status().reject_code, RejectCode::kCommLost);
  plc_.trigger = false;
  pulse(&PlcControl::error_reset);  // heartbeat still silent: stays latched
  EXPECT_TRUE(machine_.status().plc_comm_lost);
  EXPECT_EQ(machine_.status().error_code, regs::ErrorCode::kPlcCommLost);
  plc_.plc_heartbeat = 2;
  update();
  pulse(&PlcControl::error_reset);
  EXPECT_FALSE(machine_.status().plc_comm_lost);
  EXPECT_FALSE(machine_.status().error());
  EXPECT_TRUE(machine_.status().ready);
}

// The PLC goes away (cable, reboot) with a result unread; the new session finds PLC_COMM_LOST
// latched and the result still valid, and may reset and acknowledge in either order.
class CommLostWithAnUnreadResult : public MachineTest, public ::testing::WithParamInterface<bool> {
 protected:
  void lose_the_plc_with_a_result_pending() {
    update();
    plc_.plc_heartbeat = 1;
    update();
    trigger(5, 1);
    update(4s);  // the PLC is gone: its heartbeat stops while the part is analysed
    ASSERT_TRUE(machine_.status().plc_comm_lost);
    finish(regs::ResultCode::kOk, true);
    update(2min);  // a long outage: past result_ttl_s too
    ASSERT_TRUE(machine_.status().result_valid);
    ASSERT_TRUE(machine_.status().result_stale);
    ASSERT_EQ(machine_.status().error_code, regs::ErrorCode::kPlcCommLost);
    plc_.plc_heartbeat = 100;  // the new session's heartbeat starts
    update();
  }
};

TEST_P(CommLostWithAnUnreadResult, ResetAndAckInEitherOrderKeepTheResultUntilTheAck) {
  const bool reset_first = GetParam();
  lose_the_plc_with_a_result_pending();
  if (reset_first) {
    pulse(&PlcControl::error_reset);
    EXPECT_FALSE(machine_.status().plc_comm_lost);
    EXPECT_FALSE(machine_.status().error());
    EXPECT_TRUE(machine_.status().result_valid);  // the reset did not drop it
    EXPECT_TRUE(machine_.status().part_ok);
    EXPECT_EQ(machine_.status().state, State::kDone);
    pulse(&PlcControl::result_ack);
  } else {
    pulse(&PlcControl::result_ack);  // acknowledging works while PLC_COMM_LOST is set
    EXPECT_FALSE(machine_.status().result_valid);
    EXPECT_TRUE(machine_.status().plc_comm_lost);
    EXPECT_FALSE(machine_.status().ready);
    pulse(&PlcControl::error_reset);
  }
  EXPECT_FALSE(machine_.status().result_valid);
  EXPECT_FALSE(machine_.status().error());
  EXPECT_TRUE(machine_.status().ready);
  trigger(6, 1);
  EXPECT_EQ(machine_.status().trigger_count, 2);
}

INSTANTIATE_TEST_SUITE_P(Order, CommLostWithAnUnreadResult, ::testing::Values(true, false),
                         [](const ::testing::TestParamInfo<bool>& p) {
                           return p.param ? "ResetFirst" : "AckFirst";
                         });

TEST_F(MachineTest, CommLostKeepsTheCodeOfAnErrorAlreadyLatched) {
  update();
  plc_.plc_heartbeat = 1;
  update();
  trigger(1, 1);
  finish(regs::ResultCode::kScanFailed, false, regs::ErrorCode::kScanFailed);
  update(4s);
  EXPECT_TRUE(machine_.status().plc_comm_lost);
  EXPECT_EQ(machine_.status().error_code, regs::ErrorCode::kScanFailed);
  pulse(&PlcControl::error_reset);  // heartbeat still silent: code 7 takes over
  EXPECT_EQ(machine_.status().error_code, regs::ErrorCode::kPlcCommLost);
  EXPECT_EQ(machine_.status().state, State::kDone);  // the failed result, not yet acknowledged
}

TEST_F(MachineTest, TriggerNotReleasedForcesAckOffAndRaisesError) {
  update();
  plc_.trigger = true;
  ASSERT_TRUE(update().start.has_value());
  update(4900ms);
  EXPECT_TRUE(machine_.status().trigger_ack);
  const MachineStep step = update(200ms);
  EXPECT_TRUE(has(step, MachineEvent::kTriggerNotReleased));
  EXPECT_FALSE(machine_.status().trigger_ack);
  EXPECT_EQ(machine_.status().error_code, regs::ErrorCode::kTriggerNotReleased);
  EXPECT_TRUE(machine_.status().busy);  // the running job continues
  finish(regs::ResultCode::kOk, true);
  // Code 6 is a handshake error, not a failed job: STATE DONE, ERROR = 1, the result valid.
  EXPECT_EQ(machine_.status().state, State::kDone);
  EXPECT_TRUE(machine_.status().error());
  EXPECT_TRUE(machine_.status().result_valid);
  EXPECT_TRUE(machine_.status().part_ok);
  plc_.trigger = false;
  pulse(&PlcControl::error_reset);
  EXPECT_EQ(machine_.status().state, State::kDone);
  EXPECT_TRUE(machine_.status().result_valid);
}

TEST_F(MachineTest, RefusalReasons) {
  update();
  plc_.trigger_enable = false;
  plc_.trigger = true;
  update();
  EXPECT_EQ(machine_.status().reject_code, RejectCode::kNotEnabled);
  plc_.trigger = false;
  plc_.trigger_enable = true;
  online_ = false;
  update();
  EXPECT_FALSE(machine_.status().ready);
  plc_.trigger = true;
  update();
  EXPECT_EQ(machine_.status().reject_code, RejectCode::kScannerOffline);
  EXPECT_EQ(machine_.status().reject_count, 2);
}

TEST(MachineCatalogue, UnknownPartIsRejected) {
  MachineSettings settings;
  settings.known_parts = {3, 4};
  const auto t0 = Clock::time_point{} + 1h;
  InspectionMachine machine(settings, t0);
  PlcControl plc;
  plc.trigger_enable = true;
  machine.update(plc, true, t0);
  plc.part_id = 5;
  plc.trigger = true;
  EXPECT_FALSE(machine.update(plc, true, t0 + 10ms).start);
  EXPECT_EQ(machine.status().reject_code, RejectCode::kUnknownPart);
  plc.trigger = false;
  machine.update(plc, true, t0 + 20ms);
  plc.part_id = 4;
  plc.trigger = true;
  EXPECT_TRUE(machine.update(plc, true, t0 + 30ms).start);
  EXPECT_FALSE(machine.status().trigger_rejected);  // cleared by the accepted trigger
}

TEST_F(MachineTest, AckEdgeHeldHighDoesNotAcknowledgeTheNextResult) {
  update();
  trigger(1, 1);
  finish(regs::ResultCode::kOk, true);
  plc_.result_ack = true;  // the PLC acks and keeps the coil high
  update();
  EXPECT_FALSE(machine_.status().result_valid);
  plc_.trigger = true;
  ASSERT_TRUE(update().start.has_value());
  plc_.trigger = false;
  update();
  finish(regs::ResultCode::kOk, true);
  EXPECT_TRUE(machine_.status().result_valid);  // held ack is a level, not an edge
}

}  // namespace
}  // namespace springscan::daemon
