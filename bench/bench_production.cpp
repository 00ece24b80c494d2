// The whole analysis of a 1M-point one-sided scan of a real production part: the openamr side
// panel (16 bends, 214 faces, a solid 1.5 mm sheet), loaded as the station loads it (samples,
// segmentation, exact distance), produced with springback on every bend, scanned by two laser
// passes tilted +-35 deg (500k points each, sigma 0.02 mm), posed 20 deg and 50 mm off. Each
// stage's time is a counter (the report's timings_ms).
//   ./build/bench/bench_production --benchmark_repetitions=3
#include <benchmark/benchmark.h>

#include <cmath>
#include <numbers>
#include <string>

#include "analysis/cad/model.hpp"
#include "analysis/deviation/deviation.hpp"
#include "analysis/inspection/pipeline.hpp"
#include "analysis/uncertainty/frame_uncertainty.hpp"
#include "bench/inspection_loop.hpp"
#include "simulators/parts/laser_scan.hpp"
#include "simulators/parts/produced_part.hpp"
#include "tests/support/test_paths.hpp"

namespace {

using namespace springscan::analysis;
namespace parts = springscan::parts;
namespace v1 = springscan::v1;

struct Data {
  PartModel model;
  PointCloud scan;
  std::string error;
};

// The pose the scan is given in: the part 20 deg and 50 mm off.
Transform scan_pose() {
  return Transform(Eigen::Translation3d(50.0, -20.0, 10.0) *
                   Eigen::AngleAxisd(20.0 * std::numbers::pi / 180.0, Vec3(1, 2, 3).normalized()));
}

Expected<PointCloud> scan_of(const parts::ProducedPart& part) {
  parts::LaserScanSettings ls;
  ls.point_count = 500'000;
  ls.noise_sigma_mm = 0.02;
  ls.line_direction = Vec3(0.35, 1.0, 0.0).normalized();
  ls.T_scan_part = scan_pose();
  const double tilt = 35.0 * std::numbers::pi / 180.0;
  // Tilted about a diagonal of the part's edges, as in the production-parts test: every wall
  // is seen, the short tabs too (about y the walls along y are edge-on).
  const double diagonal = std::numbers::pi / 4.0;
  PointCloud out;
  for (int side : {1, -1}) {
    ls.view_direction = Vec3(side * std::sin(tilt) * std::cos(diagonal),
                             side * std::sin(tilt) * std::sin(diagonal), -std::cos(tilt));
    ls.seed = static_cast<std::uint64_t>(side + 2);
    auto pass = parts::laser_scan(part, ls);
    if (!pass) return pass.error();
    out.points.insert(out.points.end(), pass->cloud.points.begin(), pass->cloud.points.end());
  }
  return out;  // points only, as the laser driver delivers them
}

const Data& data() {
  static const Data d = [] {
    Data out;
    const std::string path =
        springscan::test_paths::shared_cad("openamr-MMP.00.00.00.003_Side_panel.step");
    auto cad = parts::load_cad_part(path);
    auto model = load_part_model(path);
    if (!cad || !model) {
      out.error = cad ? model.message() : cad.message();
      return out;
    }
    std::vector<double> springback(cad->model.segmentation.bends.size(), 1.0);
    auto produced = parts::make_produced_part(cad->model, cad->shape, springback);
    if (!produced) {
      out.error = produced.message();
      return out;
    }
    auto scan = scan_of(*produced);
    if (!scan) {
      out.error = scan.message();
      return out;
    }
    out.model = std::move(*model);
    out.scan = std::move(*scan);
    return out;
  }();
  return d;
}

void BM_InspectionSidePanel1M(benchmark::State& state) {
  const Data& d = data();
  if (!d.error.empty()) {
    state.SkipWithError(d.error.c_str());
    return;
  }
  const auto report = springscan::bench::timed_inspections(state, d.model, d.scan);
  if (!report) return;
  const v1::InspectionReport& last = *report;
  const auto& t = last.timings_ms();
  state.counters["points"] = static_cast<double>(d.scan.size());
  state.counters["reduce_ms"] = t.reduce();
  state.counters["fit_ms"] = t.global_fit();
  state.counters["deviation_ms"] = t.deviation();
  state.counters["local_fits_ms"] = t.local_fits();
  state.counters["field_ms"] = t.deformation();
  state.counters["total_ms"] = t.total();
  state.counters["residual_mm"] = last.global_fit().rms_residual();
  int measured = 0;
  for (const auto& b : last.bends()) measured += b.measured() ? 1 : 0;
  state.counters["bends_measured"] = measured;
}
BENCHMARK(BM_InspectionSidePanel1M)
    ->Arg(2)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->MeasureProcessCPUTime();

// The deviation stage alone: the exact signed distance of every point of the same scan, taken
// back to the CAD frame by its true pose, on `threads` threads (the stage the whole analysis
// spends most in; one thread gives the steadiest figure on a shared machine).
void BM_DeviationSidePanel1M(benchmark::State& state) {
  const Data& d = data();
  if (!d.error.empty()) {
    state.SkipWithError(d.error.c_str());
    return;
  }
  const PointCloud in_cad = transformed(d.scan, scan_pose().inverse());
  const KdTree no_samples{std::vector<Vec3>{}};  // the exact surface is used
  DeviationSettings settings;
  settings.threads = static_cast<int>(state.range(0));
  for (auto _ : state) {
    auto result = signed_deviation(in_cad.points, d.model, no_samples, settings);
    if (!result) {
      state.SkipWithError(result.message().c_str());
      return;
    }
    state.counters["p95_mm"] = result->statistics.p95_mm;
  }
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(in_cad.size()));
}
BENCHMARK(BM_DeviationSidePanel1M)
    ->Arg(1)
    ->Arg(2)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->MeasureProcessCPUTime();

// The uncertainty stage alone (docs/uncertainty.md) on the same scan in its true pose: the
// flanges' covariances and every bend's budget from the springback stage's result, and the result
// frame's from the reduced scan's pairs (as the pipeline gives it, 1 point in 20 here), and the
// deviation statistics' (the frame through the p95 and the largest |d|, the distances' noise and
// the outliers' shift of the p95, over the 1M points). Its share
// of BM_InspectionSidePanel1M's total is the stage's cost (issue 41: at most 5 %).
void BM_UncertaintySidePanel1M(benchmark::State& state) {
  const Data& d = data();
  if (!d.error.empty()) {
    state.SkipWithError(d.error.c_str());
    return;
  }
  const PointCloud in_cad = transformed(d.scan, scan_pose().inverse());
  const auto springback = measure_springback(d.model, in_cad);
  if (!springback) {
    state.SkipWithError(springback.message().c_str());
    return;
  }
  std::vector<Vec3> fit_points;
  for (std::size_t i = 0; i < in_cad.size(); i += 20) fit_points.push_back(in_cad.points[i]);
  const KdTree tree(d.model.samples.points);
  const auto deviation = signed_deviation(in_cad.points, d.model, tree);
  if (!deviation) {
    state.SkipWithError(deviation.message().c_str());
    return;
  }
  const std::vector<double>& dist = deviation->signed_distance_mm;
  for (auto _ : state) {
    benchmark::DoNotOptimize(estimate_uncertainty(*springback, 500.0));
    const FrameUncertainty frame = frame_uncertainty(fit_points, tree, d.model.samples.normals);
    state.counters["frame_U_mm"] = frame.translation_mm;
    // The deviation statistics' U (the pipeline's): the frame through each statistic, the noise,
    // the outliers' shift of the p95.
    const auto& normals = d.model.samples.normals;
    benchmark::DoNotOptimize(
        frame_statistic_sigma(frame, in_cad.points, dist, 0.95, tree, normals) +
        frame_statistic_sigma(frame, in_cad.points, dist, 1.0, tree, normals) +
        neighbour_noise_mm(in_cad.points, dist) + p95_outlier_shift_mm(dist));
  }
}
BENCHMARK(BM_UncertaintySidePanel1M)->Unit(benchmark::kMillisecond)->UseRealTime();

// The simulated laser scanner (simulators/parts/laser_scan.hpp) on the side panel: 200k points
// of one pass, noise 0.02 mm (was a timed unit test, LaserScan.SidePanelPointCount: timing
// belongs here, where the machine's load cannot fail a test).
void BM_LaserScanSidePanel200k(benchmark::State& state) {
  static const auto produced = []() -> Expected<parts::ProducedPart> {
    auto cad = parts::load_cad_part(
        springscan::test_paths::shared_cad("openamr-MMP.00.00.00.003_Side_panel.step"));
    if (!cad) return cad.error();
    std::vector<double> springback(cad->model.segmentation.bends.size(), 2.0);
    return parts::make_produced_part(cad->model, cad->shape, springback);
  }();
  if (!produced) {
    state.SkipWithError(produced.message().c_str());
    return;
  }
  parts::LaserScanSettings settings;
  settings.point_count = 200'000;
  settings.noise_sigma_mm = 0.02;
  for (auto _ : state) {
    auto scan = parts::laser_scan(*produced, settings);
    if (!scan) {
      state.SkipWithError(scan.message().c_str());
      return;
    }
    state.counters["points"] = static_cast<double>(scan->cloud.size());
  }
}
BENCHMARK(BM_LaserScanSidePanel200k)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
