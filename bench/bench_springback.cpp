// Local fits and the bend table for a hat-profile scan (budget: 1M points in 150 ms
// on 2 cores). The scan is simulated once, already in the CAD frame with a small pose error
// left over from the global fit; each iteration runs measure_springback on it. The shaped case
// is the same hat with a curled wall, a twist and springback varying along the bends: what the
// flange-shape and angle-along-the-bend steps cost when every flange has something to find.
#include <benchmark/benchmark.h>

#include <cmath>
#include <memory>
#include <numbers>

#include "analysis/springback/springback.hpp"
#include "simulators/parts/shaped_profile.hpp"
#include "simulators/parts/sheet_part.hpp"

namespace {

using namespace springscan::analysis;
using namespace springscan::parts;

constexpr double kDeg = std::numbers::pi / 180.0;
const std::vector<double> kSpringbackDeg = {1.2, 2.0, -0.4, 1.6};

struct Fixture {
  PartModel model;
  PointCloud scan;
};

const Fixture& fixture(std::int64_t points) {
  static std::unique_ptr<Fixture> cached;
  static std::int64_t cached_points = -1;
  if (cached_points == points) return *cached;
  const ProfileSpec spec = hat_profile(30, 40, 60, 90, 4);
  auto model = profile_part_model(spec, {.sample_count = 40000});
  ScanSimulationSettings st;
  st.point_count = points;
  st.noise_sigma_mm = 0.02;
  st.T_scan_part = Eigen::Translation3d(0.2, -0.1, 0.15) *
                   Eigen::AngleAxisd(0.3 * kDeg, Vec3(1, 2, 3).normalized());
  auto scan = simulate_scan(spec, kSpringbackDeg, st);
  cached = std::make_unique<Fixture>(Fixture{std::move(model).value(), std::move(scan).value()});
  cached_points = points;
  return *cached;
}

void BM_MeasureSpringback(benchmark::State& state) {
  const Fixture& f = fixture(state.range(0));
  SpringbackSettings settings;
  settings.threads = static_cast<int>(state.range(1));
  settings.max_scan_points = state.range(2);
  double worst_error = 0.0;
  for (auto _ : state) {
    const auto result = measure_springback(f.model, f.scan, settings);
    if (!result) {
      state.SkipWithError(result.message().c_str());
      return;
    }
    for (std::size_t b = 0; b < result->bends.size(); ++b)
      worst_error =
          std::max(worst_error, std::abs(result->bends[b].springback_deg - kSpringbackDeg[b]));
  }
  state.counters["worst_error_deg"] = worst_error;
  state.SetItemsProcessed(state.iterations() * state.range(0));
}
// Args: scan points, threads, max_scan_points (0 = every point).
BENCHMARK(BM_MeasureSpringback)
    ->Args({200'000, 2, 100'000})
    ->Args({1'000'000, 1, 100'000})
    ->Args({1'000'000, 2, 100'000})
    ->Args({1'000'000, 2, 0})
    ->Unit(benchmark::kMillisecond)
    ->MeasureProcessCPUTime()
    ->UseRealTime();

const Fixture& shaped_fixture() {
  static const Fixture fixture = [] {
    ProfileSpec spec = hat_profile(30, 40, 60, 90, 4);
    spec.width_mm = 200;
    ProfileShape shape;
    shape.springback_deg = kSpringbackDeg;
    shape.springback_gradient_deg_per_100mm = {0.5, -0.5, 1.0, 0.0};
    shape.curl_radius_mm = {0, 200, 0, -400, 0};
    shape.twist_deg_per_100mm = 0.3;
    ScanSimulationSettings st;
    st.point_count = 1'000'000;
    st.noise_sigma_mm = 0.02;
    st.T_scan_part = Eigen::Translation3d(0.2, -0.1, 0.15) *
                     Eigen::AngleAxisd(0.3 * kDeg, Vec3(1, 2, 3).normalized());
    auto model = profile_part_model(spec, {.sample_count = 40000});
    auto scan = simulate_shaped_scan(spec, shape, st);
    return Fixture{std::move(model).value(), std::move(scan).value()};
  }();
  return fixture;
}

void BM_MeasureSpringbackShaped(benchmark::State& state) {
  const Fixture& f = shaped_fixture();
  SpringbackSettings settings;
  settings.threads = static_cast<int>(state.range(0));
  std::size_t stations = 0;
  for (auto _ : state) {
    const auto result = measure_springback(f.model, f.scan, settings);
    if (!result) {
      state.SkipWithError(result.message().c_str());
      return;
    }
    stations = 0;
    for (const auto& bend : result->bends) stations += bend.stations.size();
  }
  state.counters["stations"] = static_cast<double>(stations);
  state.SetItemsProcessed(state.iterations() * 1'000'000);
}
// Args: threads. 1M points, thinned to the default 100k.
BENCHMARK(BM_MeasureSpringbackShaped)
    ->Arg(1)
    ->Arg(2)
    ->Unit(benchmark::kMillisecond)
    ->MeasureProcessCPUTime()
    ->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
