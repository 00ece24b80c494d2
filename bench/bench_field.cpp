// The deformation field and the compensation for a 1M-point scan (budget 100 ms on
// 2 cores, docs/performance.md "Deformation field"): the raw min-cost matching of the k-center
// reductions, its refinement (flange motions and the scan's local surface) and the
// compensation at the control points. Inputs (reduction, springback stage) are built once.
//   bench_field [google benchmark flags]
#include <benchmark/benchmark.h>

#include "analysis/core/kdtree.hpp"
#include "analysis/matching/compensation.hpp"
#include "analysis/matching/deformation_field.hpp"
#include "analysis/matching/field_refinement.hpp"
#include "analysis/preprocess/reduction.hpp"
#include "analysis/springback/springback.hpp"
#include "simulators/parts/sheet_part.hpp"

namespace {

using namespace springscan::analysis;
using namespace springscan::parts;

struct Fixture {
  PartModel model;
  PointCloud scan;
  ReductionOutcome reduced;
  SpringbackResult springback;
  std::vector<Vec3> normals;
  std::vector<int> faces;
};

// The springback bench's hat (docs/performance.md "Springback"), sprung open, in the CAD frame.
const Fixture& fixture(std::int64_t points) {
  static std::map<std::int64_t, Fixture> cache;
  if (auto it = cache.find(points); it != cache.end()) return it->second;
  Fixture f;
  const ProfileSpec hat = hat_profile(30.0, 40.0, 60.0, 90.0, 4.0);
  f.model = *profile_part_model(hat, {.sample_count = 40000});
  ScanSimulationSettings scan;
  scan.point_count = points;
  scan.noise_sigma_mm = 0.02;
  f.scan = *simulate_scan(hat, {1.2, 2.0, -0.4, 1.6}, scan);
  f.reduced = *reduce(f.scan, f.model.samples);
  f.springback = *measure_springback(f.model, f.scan);
  const KdTree samples(f.model.samples.points);
  for (const Vec3& c : f.reduced.model_centers) {
    const std::size_t k = samples.nearest(c)->index;
    f.normals.push_back(f.model.samples.normals[k]);
    f.faces.push_back(f.model.samples.face_ids[k]);
  }
  return cache.emplace(points, std::move(f)).first->second;
}

void BM_FieldAndCompensation(benchmark::State& state) {
  const Fixture& f = fixture(state.range(0));
  const int threads = static_cast<int>(state.range(1));
  DeformationFieldSettings settings;
  settings.refinement.threads = threads;
  std::size_t covered = 0;
  for (auto _ : state) {
    auto raw = deformation_field(f.reduced.model_centers, f.reduced.scan_centers, settings);
    const FieldRefinementInput input{f.reduced.model_centers, f.normals,     f.faces,
                                     f.model.segmentation,    &f.springback, f.scan.points,
                                     f.model.samples.points,  nullptr};
    const DeformationField field = refine_field(*raw, input, settings.refinement);
    auto comp = compensation(field, f.reduced.model_centers);
    covered = field.vectors.size();
    benchmark::DoNotOptimize(comp);
  }
  state.counters["control_points"] = static_cast<double>(f.reduced.model_centers.size());
  state.counters["covered"] = static_cast<double>(covered);
}
BENCHMARK(BM_FieldAndCompensation)
    ->Args({200000, 2})
    ->Args({1000000, 1})
    ->Args({1000000, 2})
    ->Unit(benchmark::kMillisecond)
    ->MeasureProcessCPUTime()
    ->UseRealTime();

// The refinement alone (the raw matching's cost is in bench_matching).
void BM_Refinement(benchmark::State& state) {
  const Fixture& f = fixture(state.range(0));
  DeformationFieldSettings settings;
  settings.refinement.threads = 2;
  const auto raw = deformation_field(f.reduced.model_centers, f.reduced.scan_centers, settings);
  const FieldRefinementInput input{f.reduced.model_centers, f.normals,     f.faces,
                                   f.model.segmentation,    &f.springback, f.scan.points,
                                   f.model.samples.points,  nullptr};
  for (auto _ : state) benchmark::DoNotOptimize(refine_field(*raw, input, settings.refinement));
}
BENCHMARK(BM_Refinement)
    ->Arg(1000000)
    ->Unit(benchmark::kMillisecond)
    ->MeasureProcessCPUTime()
    ->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
