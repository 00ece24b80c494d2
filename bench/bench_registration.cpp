// Speed target: a 1M-point scan against a 100k-point model on 2 cores, reduction + PCA
// + ICP to convergence + signed deviation of all 1M points in <= 400 ms (run_inspection).
// With SPRINGSCAN_BENCH_DATA_DIR set, the same data is written there as model.ply / scan.ply
// for bench/reference_open3d.py.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cstdlib>
#include <random>
#include <string>

#include "analysis/inspection/pipeline.hpp"
#include "analysis/io/point_io.hpp"
#include "analysis/registration/boundary.hpp"
#include "analysis/registration/global_fit.hpp"
#include "bench/inspection_loop.hpp"
#include "tests/analysis/synthetic.hpp"

namespace {

using namespace springscan::analysis;
namespace v1 = springscan::v1;

// An asymmetric four-flange profile, 200 mm wide.
ProfileSpec part_spec(double springback_deg) {
  ProfileSpec spec;
  spec.flange_lengths_mm = {80, 60, 120, 40};
  spec.bend_angles_deg = {90 - springback_deg, -60 + springback_deg, 45 - springback_deg};
  spec.bend_radii_mm = {5, 8, 6};
  spec.width_mm = 200;
  return spec;
}

struct Data {
  PartModel model;
  PointCloud scan;
};

const Data& data() {
  static const Data d = [] {
    Data out;
    out.model.samples = testing::sample_profile(part_spec(0.0), 100'000, 1);
    out.scan = testing::sample_profile(part_spec(1.0), 1'000'000, 2);
    out.scan.normals.clear();
    // A line scanner delivers points line by line: sort by the extrusion coordinate (0.5 mm
    // lines), then along the profile. (Random order costs the nearest searches about 2x in
    // cache misses; see docs/performance.md.)
    std::sort(out.scan.points.begin(), out.scan.points.end(), [](const Vec3& a, const Vec3& b) {
      const int la = static_cast<int>(a.y() / 0.5), lb = static_cast<int>(b.y() / 0.5);
      return la != lb ? la < lb : a.x() + a.z() < b.x() + b.z();
    });
    testing::add_noise(out.scan.points, 0.02, 3);
    testing::add_outliers(out.scan.points, 0.01, 5.0, 4);
    // The scan frame: 2 degrees and a few mm off the CAD frame.
    Transform T_scan_cad = Transform::Identity();
    T_scan_cad.linear() =
        Eigen::AngleAxisd(2.0 * 3.14159265358979 / 180.0, Vec3(1, 2, 3).normalized()).matrix();
    T_scan_cad.translation() = Vec3(3.0, -2.0, 1.0);
    for (auto& p : out.scan.points) p = T_scan_cad * p;
    if (const char* dir = std::getenv("SPRINGSCAN_BENCH_DATA_DIR")) {
      PointWriteOptions options;
      (void)write_point_cloud(std::string(dir) + "/model.ply", out.model.samples, options);
      (void)write_point_cloud(std::string(dir) + "/scan.ply", out.scan, options);
    }
    return out;
  }();
  return d;
}

void BM_Inspection1MScan100kModel(benchmark::State& state) {
  const Data& d = data();
  const auto report = springscan::bench::timed_inspections(state, d.model, d.scan);
  if (!report) return;
  const v1::InspectionReport& last = *report;
  state.counters["reduce_ms"] = last.timings_ms().reduce();
  state.counters["fit_ms"] = last.timings_ms().global_fit();
  state.counters["deviation_ms"] = last.timings_ms().deviation();
  state.counters["icp_iterations"] = last.global_fit().iterations();
  state.counters["rms_final_mm"] = last.global_fit().rms_final();
  state.counters["deviation_rms_mm"] = last.deviation().rms();
}
BENCHMARK(BM_Inspection1MScan100kModel)
    ->Arg(2)
    ->Arg(1)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->MeasureProcessCPUTime();

}  // namespace

// The boundary stage alone (registration/boundary.hpp) after the global fit: the profile's
// length is free for the surface, its ends pin it.
void BM_Boundary1MScan(benchmark::State& state) {
  const Data& d = data();
  static const KdTree tree(d.model.samples.points);
  static const Transform T = [&d] {
    GlobalFitSettings s;
    auto fit = global_fit(d.scan.points, tree, d.model.samples.normals, s);
    return fit ? fit->T_cad_scan : Transform::Identity();
  }();
  double shift = 0.0;
  for (auto _ : state) {
    auto pinned = pin_to_boundary(d.scan.points, T, d.model, tree);
    if (!pinned) {
      state.SkipWithError(pinned.message().c_str());
      return;
    }
    shift = pinned->free_directions.empty() ? 0.0 : pinned->free_directions[0].shift_mm;
    benchmark::DoNotOptimize(pinned->T_cad_scan);
  }
  state.counters["shift_mm"] = shift;
}
BENCHMARK(BM_Boundary1MScan)->Unit(benchmark::kMillisecond)->MeasureProcessCPUTime()->UseRealTime();

BENCHMARK_MAIN();
