#pragma once
// Internals of the fault campaign, shared by fault_campaign.cpp (the cycles and their faults),
// campaign_plc.cpp (the PLC program: handshake, reconnection, recovery), campaign_checks.cpp
// (every result it collects checked) and campaign_report.cpp (the figures). Not an interface.

#include <array>
#include <chrono>
#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <random>
#include <set>
#include <string>
#include <vector>

#include "bench/fault_campaign.hpp"
#include "bench/result_oracle.hpp"
#include "bench/soak_common.hpp"
#include "bench/soak_supervisor.hpp"
#include "simulators/plc_client.hpp"
#include "simulators/usb_emulator.hpp"

namespace springscan::bench {

namespace regs = daemon::regs;
using Clock = std::chrono::steady_clock;

/// What a cycle does to the station (issue 19's list; kHaltCleared is the halt the driver
/// clears by itself, kStuckHalt the one it cannot: "stalled endpoint").
enum class FaultKind : int {
  kNone,
  kUnplug,            ///< the cable pulled mid-scan, plugged back after the result
  kHaltCleared,       ///< bulk IN halts once mid-scan (CLEAR_HALT works)
  kStuckHalt,         ///< bulk IN halts and stays halted: stalled endpoint, power-cycled after
  kBadCrc,            ///< one data frame with a corrupted CRC
  kSequenceGap,       ///< one data frame skips a frame sequence number
  kScanTimeout,       ///< the device goes silent mid-scan (scanner.timeout_s)
  kDropAfterTrigger,  ///< the PLC disconnects right after writing TRIGGER (TRIG_ACK unseen)
  kDropAfterAck,      ///< ... after TRIG_ACK, having dropped TRIGGER
  kDropWhileBusy,     ///< ... while waiting for RESULT_VALID
  kDropBeforeAck,     ///< ... after reading the result, before RESULT_ACK
  kHeartbeatLoss,     ///< PLC_HEARTBEAT stops until PLC_COMM_LOST, then runs again
  kKill,              ///< springscand killed with SIGKILL at a random moment, restarted
  kCount,
};
inline constexpr int kFaultKinds = static_cast<int>(FaultKind::kCount);
const char* fault_name(FaultKind kind);

/// The figures of one fault kind.
struct KindFigures {
  int cycles = 0;
  std::vector<double> cycle_ms;         ///< trigger -> the cycle's result collected, recovered
  std::map<std::string, int> outcomes;  ///< what the PLC saw, e.g. "RESULT_CODE 3, DETAIL 5"
};

struct Tally {
  // Failures: each must stay 0.
  int lost = 0;         ///< accepted, then neither a result nor an error the PLC can see
  int duplicated = 0;   ///< a job's result shown valid twice (a new seq, or again after ACK)
  int stale = 0;        ///< RESULT_VALID whose registers are not the stored report of that job
  int unrecovered = 0;  ///< the station did not come back to READY (the campaign stops)
  std::vector<std::string> notes;  ///< one line per failure
  // Outcomes.
  int collected = 0;                ///< results read with RESULT_VALID = 1 and acknowledged
  int collected_after_restart = 0;  ///< stored before a kill, read from the restored block
  int interrupted = 0;  ///< killed before its report was stored: BOOT_ID changed, no record
  int error_only = 0;   ///< ended with ERROR and no result (e.g. ERROR_CODE 5)
  int refused = 0;      ///< a trigger refused although READY was 1
  /// Results that do not say what was injected: a scan failure in a cycle without a device
  /// fault, or a device fault reported with another ERROR_DETAIL.
  int misreported = 0;
  std::array<KindFigures, kFaultKinds> kinds;
  // springscand's resources, sampled after every cycle (station idle).
  Usage first, peak, last;
  long fd_growth_in_one_life = 0;  ///< the largest fds increase within one process's life
  /// The longest-lived springscand: its cycles and its first and last samples.
  int longest_life_cycles = 0;
  Usage longest_life_first, longest_life_last;
  int cycles_run = 0;
  int failures() const { return lost + duplicated + stale + unrecovered + misreported; }
};

/// A result as the PLC read it: the block raw and decoded (with the vectors), one RESULT_SEQ.
struct ResultRegisters {
  BlockWords block;
  simulators::ResultRead read;
};

struct CampaignPaths {
  std::string dir;      ///< the campaign's temporary directory
  std::string config;   ///< springscand's config
  std::string reports;  ///< report_dir
  std::string log;      ///< springscand's output
};

class Campaign {
 public:
  Campaign(const CampaignSettings& settings, const CampaignPaths& paths,
           simulators::EmulatedUsbScanner& emulator, Supervisor& station);
  /// Runs the cycles; false when the station did not recover (the rest is not run).
  bool run();
  const Tally& tally() const { return tally_; }

 private:
  // The cycle and its fault (fault_campaign.cpp).
  FaultKind draw();
  bool run_cycle(std::uint16_t job);
  void arm_device(FaultKind kind);
  void inject_after_trigger(FaultKind kind);
  void repair_after(FaultKind kind);
  void sample_usage();
  double uniform(double lo, double hi);

  // The PLC program (campaign_plc.cpp).
  bool reconnect();
  void drop_connection();
  void pause_disconnected();
  void idle(double seconds);
  bool make_ready();
  bool trigger(std::uint16_t job, FaultKind kind);
  bool collect(std::uint16_t job, bool drop_before_ack);
  bool take_result(std::uint16_t job, bool& drop_before_ack);
  bool finish_result(const simulators::StationStatus& status, std::uint16_t seq);
  void after_restart(std::uint16_t job, const simulators::StationStatus& status);
  bool read_block(ResultRegisters& out);
  void check_result(std::uint16_t job, const ResultRegisters& read, const char* how);
  void outcome(const std::string& text);
  void expect_reported(const simulators::StationStatus& status, regs::ResultCode code);
  void fail(int& counter, const std::string& note);

  CampaignSettings settings_;
  CampaignPaths paths_;
  simulators::EmulatedUsbScanner& emulator_;
  Supervisor& station_;
  std::mt19937 draws_;  ///< the faults only: the same seed gives the same sequence of faults
  std::mt19937 rng_;    ///< where and when each fault strikes, the PLC's choices
  std::unique_ptr<simulators::PlcClient> plc_;
  Tally tally_;
  FaultKind kind_ = FaultKind::kNone;  ///< this cycle's fault
  std::uint16_t boot_id_ = 0;          ///< BOOT_ID the PLC last saw
  simulators::StationStatus before_;   ///< the status when READY was seen, before the trigger
  std::set<std::uint16_t> collected_jobs_;
  std::set<std::uint16_t> acked_seqs_;
  std::optional<std::uint16_t> unacked_seq_;  ///< read, checked, not yet acknowledged
  /// Per springscand process: its first sample (scanner open) and the cycles it served.
  struct Life {
    Usage first;
    int cycles = 0;
  };
  std::map<pid_t, Life> lives_;
};

/// "RESULT_CODE 3, ERROR_CODE 2 DETAIL 5": a result as the PLC saw it, for the outcome table.
std::string result_text(const simulators::StationStatus& status, regs::ResultCode code);

/// Prints the campaign's figures (campaign_report.cpp); `final_stop_status` is the wait status
/// of the last SIGTERM.
void print_campaign(const CampaignSettings& settings, const Tally& tally, const Supervisor& station,
                    double wall_s, int final_stop_status);

}  // namespace springscan::bench
