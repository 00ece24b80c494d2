// The HTML report for a 1M-point scan (its budget: <= 300 ms), and its parts: the subsample, one
// rendered view, one PNG. The scan is the synthetic hat profile of tests/report.
#include <benchmark/benchmark.h>

#include <map>

#include "report/figures.hpp"
#include "report/raster.hpp"
#include "report/report_html.hpp"
#include "tests/report/report_fixture.hpp"

namespace {

using namespace springscan::report;

const testing::Fixture& fixture(std::size_t points) {
  static std::map<std::size_t, testing::Fixture> cache;
  auto it = cache.find(points);
  if (it == cache.end()) it = cache.emplace(points, testing::make_fixture(points)).first;
  return it->second;
}

void BM_RenderReportHtml(benchmark::State& state) {
  const auto& f = fixture(static_cast<std::size_t>(state.range(0)));
  std::size_t bytes = 0;
  for (auto _ : state) {
    auto html = render_report_html(f.report, f.cloud);
    bytes = html->size();
    benchmark::DoNotOptimize(html);
  }
  state.counters["html_MB"] = static_cast<double>(bytes) / 1e6;
}
BENCHMARK(BM_RenderReportHtml)
    ->Arg(100'000)
    ->Arg(1'000'000)
    ->MeasureProcessCPUTime()
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);

void BM_DrawCloud(benchmark::State& state) {
  const auto& f = fixture(1'000'000);
  for (auto _ : state) benchmark::DoNotOptimize(make_draw_cloud(f.cloud, 1.0, {}));
}
BENCHMARK(BM_DrawCloud)->Unit(benchmark::kMillisecond);

void BM_RenderOneView(benchmark::State& state) {
  const DrawCloud cloud = make_draw_cloud(fixture(1'000'000).cloud, 1.0, {});
  const auto view = fit_view(cloud.points, ViewKind::kIsometric);
  for (auto _ : state)
    benchmark::DoNotOptimize(render_points(cloud.points, cloud.deviation_colors, view, {2}));
}
BENCHMARK(BM_RenderOneView)->Unit(benchmark::kMillisecond);

void BM_EncodePng(benchmark::State& state) {
  const DrawCloud cloud = make_draw_cloud(fixture(1'000'000).cloud, 1.0, {});
  const auto image = render_points(cloud.points, cloud.deviation_colors,
                                   fit_view(cloud.points, ViewKind::kIsometric), {2});
  for (auto _ : state)
    state.counters["png_kB"] =
        static_cast<double>(encode_png(image, {static_cast<int>(state.range(0))})->size()) / 1e3;
}
BENCHMARK(BM_EncodePng)->Arg(1)->Arg(3)->Arg(6)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
