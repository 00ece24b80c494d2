// k-center reduction of 1M points to 5,000 centers, the spatially pruned version
// against the naive O(n k) loop; both must select exactly the same centers.
#include <benchmark/benchmark.h>

#include "analysis/preprocess/kcenter.hpp"
#include "tests/analysis/synthetic.hpp"

namespace {

using namespace springscan::analysis;

const std::vector<Vec3>& points() {
  static const std::vector<Vec3> p = testing::bumpy_surface(1'000'000, 7).points;
  return p;
}

const KCenterSettings kSettings{5000, 0.0, 0, 128};

void BM_KCenterFast(benchmark::State& state) {
  KCenterSettings s = kSettings;
  s.bucket_size = static_cast<std::size_t>(state.range(0));
  for (auto _ : state) benchmark::DoNotOptimize(kcenter_reduce(points(), s));
}
BENCHMARK(BM_KCenterFast)->Arg(64)->Arg(128)->Arg(256)->Unit(benchmark::kMillisecond);

void BM_KCenterNaive(benchmark::State& state) {
  for (auto _ : state) benchmark::DoNotOptimize(kcenter_reduce_naive(points(), kSettings));
}
BENCHMARK(BM_KCenterNaive)->Iterations(1)->Unit(benchmark::kMillisecond);

void BM_KCenterSameCenters(benchmark::State& state) {
  for (auto _ : state) {
    const auto fast = kcenter_reduce(points(), kSettings);
    const auto naive = kcenter_reduce_naive(points(), kSettings);
    if (!fast || !naive || fast->centers != naive->centers)
      state.SkipWithError("fast and naive k-center selected different centers");
    state.counters["covering_radius_mm"] = fast->covering_radius_mm;
  }
}
BENCHMARK(BM_KCenterSameCenters)->Iterations(1)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
