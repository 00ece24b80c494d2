// The whole analysis of a 1M-point scan (issue 37): what `springscan analyze` runs
// (run_inspection, every stage), on the demo hat profile (demo/hat-profile.step, 4 bends) as
// produced and scanned 1M times (simulators/parts/sheet_part.hpp, the demo's springback, noise,
// outliers and pose; coordinates rounded to float as a binary float PLY keeps them), in three
// point orders: shuffled (a file's or a merged multi-head scan's order), sorted by 2 mm grid
// cell, and in scanner lines. The argument is the order; each stage's time is a counter (the
// report's timings_ms). The side panel's figures are bench_production's.
//   ./build/bench/bench_analysis --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
// With SPRINGSCAN_BENCH_POINTS set (e.g. 100000), a smaller scan: the quick run of
// scripts/perf-compare.sh --quick.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <random>
#include <string>

#include "analysis/cad/model.hpp"
#include "analysis/core/spatial_order.hpp"
#include "analysis/inspection/pipeline.hpp"
#include "bench/inspection_loop.hpp"
#include "simulators/parts/demo_hat.hpp"
#include "simulators/parts/sheet_part.hpp"
#include "tests/support/test_paths.hpp"

namespace {

using namespace springscan::analysis;
namespace parts = springscan::parts;
namespace v1 = springscan::v1;

enum Order { kShuffled = 0, kGridSorted = 1, kScanLines = 2 };

struct Data {
  PartModel model;
  PointCloud scan;  // in the simulator's order
  std::string error;
};

std::int64_t point_count() {
  const char* n = std::getenv("SPRINGSCAN_BENCH_POINTS");
  return n ? std::max<std::int64_t>(1000, std::atoll(n)) : 1'000'000;
}

const Data& data() {
  static const Data d = [] {
    Data out;
    auto model = load_part_model(springscan::test_paths::source("demo/hat-profile.step"));
    parts::ScanSimulationSettings s;
    s.point_count = point_count();
    s.noise_sigma_mm = 0.02;
    s.outlier_fraction = 0.005;
    s.T_scan_part = parts::demo_hat_pose();
    auto scan = parts::simulate_scan(parts::demo_hat_profile(), parts::kDemoHatSpringbackDeg, s);
    if (!model || !scan) {
      out.error = model ? scan.message() : model.message();
      return out;
    }
    for (Vec3& p : scan->points) p = p.cast<float>().cast<double>();
    out.model = std::move(*model);
    out.scan = std::move(*scan);
    return out;
  }();
  return d;
}

// The points in `order`. Grid cells and lines are taken in the part's frame (as a scanner
// moving along the hat's extrusion, +y, delivers them), their order in the scan frame's terms.
PointCloud ordered(const PointCloud& scan, Order order) {
  PointCloud out = scan;
  if (order == kShuffled) {
    std::mt19937_64 rng(37);
    std::shuffle(out.points.begin(), out.points.end(), rng);
    return out;
  }
  const Transform T_part_scan = parts::demo_hat_pose().inverse();
  const double cell = order == kGridSorted ? 2.0 : 0.5;
  const auto key = [&](const Vec3& p) {
    const Vec3 q = T_part_scan * p;
    const auto c = [&](double v) { return static_cast<long>(std::floor(v / cell)); };
    return order == kGridSorted ? std::make_tuple(c(q.x()), c(q.y()), c(q.z()), 0.0)
                                : std::make_tuple(c(q.y()), 0L, 0L, q.x());
  };
  std::sort(out.points.begin(), out.points.end(),
            [&](const Vec3& a, const Vec3& b) { return key(a) < key(b); });
  return out;
}

void BM_AnalysisHat1M(benchmark::State& state) {
  const Data& d = data();
  if (!d.error.empty()) {
    state.SkipWithError(d.error.c_str());
    return;
  }
  const PointCloud scan = ordered(d.scan, static_cast<Order>(state.range(0)));
  const auto report = springscan::bench::timed_inspections(state, d.model, scan, 0);
  if (!report) return;
  const auto& t = report->timings_ms();
  state.counters["points"] = static_cast<double>(scan.size());
  state.counters["reduce_ms"] = t.reduce();
  state.counters["fit_ms"] = t.global_fit();
  state.counters["deviation_ms"] = t.deviation();
  state.counters["local_fits_ms"] = t.local_fits();
  state.counters["field_ms"] = t.deformation();
  state.counters["total_ms"] = t.total();
  state.counters["residual_mm"] = report->global_fit().rms_residual();
  state.counters["p95_mm"] = report->deviation().p95();
  double springback_sum = 0.0;
  for (const auto& b : report->bends()) springback_sum += b.springback_deg();
  state.counters["springback_sum_deg"] = springback_sum;
}
BENCHMARK(BM_AnalysisHat1M)
    ->ArgName("order")
    ->Arg(kShuffled)
    ->Arg(kGridSorted)
    ->Arg(kScanLines)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->MeasureProcessCPUTime();

// The reordering alone (analysis/core/spatial_order.hpp) of the shuffled scan, on 1 and 2
// threads: the search order, and the canonical order run_inspection takes a shuffled scan in.
template <typename Order>
void reorder_1m(benchmark::State& state, Order&& order_of) {
  const Data& d = data();
  const PointCloud scan = ordered(d.scan, kShuffled);
  for (auto _ : state) {
    auto order = order_of(scan.points, static_cast<int>(state.range(0)));
    benchmark::DoNotOptimize(order.data());
  }
}
void BM_SpatialOrder1M(benchmark::State& state) {
  reorder_1m(state,
             [](const std::vector<Vec3>& p, int threads) { return spatial_order(p, threads); });
}
void BM_CanonicalOrder1M(benchmark::State& state) {
  reorder_1m(state,
             [](const std::vector<Vec3>& p, int threads) { return canonical_order(p, threads); });
}
BENCHMARK(BM_SpatialOrder1M)
    ->Arg(1)
    ->Arg(2)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->MeasureProcessCPUTime();
BENCHMARK(BM_CanonicalOrder1M)
    ->Arg(1)
    ->Arg(2)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->MeasureProcessCPUTime();

}  // namespace

BENCHMARK_MAIN();
