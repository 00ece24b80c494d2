// The fault campaign's figures, as docs/reliability.md quotes them.
#include <cstdio>

#include "bench/fault_campaign_internal.hpp"

namespace springscan::bench {

namespace {

void print_kinds(const Tally& tally) {
  std::printf("| fault | cycles | cycle p50 / p95 / max (ms) | what the PLC saw |\n");
  std::printf("| --- | --- | --- | --- |\n");
  for (int k = 0; k < kFaultKinds; ++k) {
    const KindFigures& f = tally.kinds[static_cast<std::size_t>(k)];
    std::string seen;
    for (const auto& [text, n] : f.outcomes)
      seen += (seen.empty() ? "" : "; ") + std::to_string(n) + "x " + text;
    std::printf("| %s | %d | %.0f / %.0f / %.0f | %s |\n", fault_name(static_cast<FaultKind>(k)),
                f.cycles, percentile(f.cycle_ms, 0.5), percentile(f.cycle_ms, 0.95),
                percentile(f.cycle_ms, 1.0), seen.c_str());
  }
}

}  // namespace

void print_campaign(const CampaignSettings& s, const Tally& tally, const Supervisor& station,
                    double wall_s, int final_stop_status) {
  std::vector<double> all;
  for (const auto& f : tally.kinds) all.insert(all.end(), f.cycle_ms.begin(), f.cycle_ms.end());
  std::printf(
      "fault campaign: %d of %d cycles, seed %u; scan %d profiles x %d points over %.2f s; "
      "wall %.0f s\n",
      tally.cycles_run, s.cycles, s.seed, static_cast<int>(80.0 / s.step_mm) + 1,
      s.points_per_profile, s.scan_s, wall_s);
  print_kinds(tally);
  std::printf(
      "results: %d collected with RESULT_VALID, %d from the restored block after a restart, "
      "%d interrupted by a restart (no report, BOOT_ID changed), %d error without result, "
      "%d triggers refused\n",
      tally.collected, tally.collected_after_restart, tally.interrupted, tally.error_only,
      tally.refused);
  std::printf(
      "cycle time (trigger -> result collected, fault repaired), all cycles: p50 %.0f ms, "
      "p95 %.0f ms, max %.0f ms\n",
      percentile(all, 0.5), percentile(all, 0.95), percentile(all, 1.0));
  std::printf(
      "springscand: %d starts (%d SIGKILLs by the campaign), final SIGTERM: %s\n", station.starts(),
      station.kills(),
      final_stop_status == 0 ? "clean exit 0" : describe_wait_status(final_stop_status).c_str());
  std::printf(
      "springscand RSS kB start / max / end: %ld / %ld / %ld; open fds: %ld / %ld / %ld; "
      "largest fd growth within one process life: %ld\n",
      tally.first.rss_kb, tally.peak.rss_kb, tally.last.rss_kb, tally.first.fds, tally.peak.fds,
      tally.last.fds, tally.fd_growth_in_one_life);
  std::printf("longest-lived springscand: %d cycles, RSS %ld -> %ld kB, open fds %ld -> %ld\n",
              tally.longest_life_cycles, tally.longest_life_first.rss_kb,
              tally.longest_life_last.rss_kb, tally.longest_life_first.fds,
              tally.longest_life_last.fds);
  std::printf(
      "FAILURES: crashes %d, lost %d, duplicated %d, stale %d, misreported %d, unrecovered %d\n",
      station.crashes(), tally.lost, tally.duplicated, tally.stale, tally.misreported,
      tally.unrecovered);
  for (const auto& note : station.crash_notes()) std::printf("  crash: %s\n", note.c_str());
  for (const auto& note : tally.notes) std::printf("  %s\n", note.c_str());
}

}  // namespace springscan::bench
