#pragma once
// The timed loop of the whole-analysis benchmarks: run_inspection on `threads` (the benchmark's
// argument unless given; 0 = all cores) every iteration; the last report for the counters, or
// nothing (the benchmark is then marked skipped with the error).
#include <benchmark/benchmark.h>

#include <optional>

#include "analysis/inspection/pipeline.hpp"

namespace springscan::bench {

inline std::optional<v1::InspectionReport> timed_inspections(benchmark::State& state,
                                                             const analysis::PartModel& model,
                                                             const analysis::PointCloud& scan,
                                                             int threads) {
  v1::AnalysisSettings settings;
  settings.set_threads(threads);
  v1::InspectionReport last;
  for (auto _ : state) {
    auto outcome = analysis::run_inspection(model, scan, settings);
    if (!outcome) {
      state.SkipWithError(outcome.message().c_str());
      return std::nullopt;
    }
    last = std::move(outcome->report);
  }
  return last;
}

inline std::optional<v1::InspectionReport> timed_inspections(benchmark::State& state,
                                                             const analysis::PartModel& model,
                                                             const analysis::PointCloud& scan) {
  return timed_inspections(state, model, scan, static_cast<int>(state.range(0)));
}

}  // namespace springscan::bench
