// CAD side: load + tessellate + sample a ~50-face part, and exact distance queries.
// The part: a 12-flange zig-zag sheet profile, 1.5 mm thick, as a solid written to STEP
// (23 reference-side faces, 23 offset-side faces, 2 end faces, 2 side faces = 50 faces).
#include <benchmark/benchmark.h>

#include <filesystem>
#include <random>

#include "analysis/cad/distance.hpp"
#include "analysis/cad/sampling.hpp"
#include "simulators/parts/cad_profile.hpp"

namespace {

using namespace springscan::analysis;
using namespace springscan::parts;

ProfileSpec fifty_face_profile() {
  ProfileSpec spec;
  for (int i = 0; i < 12; ++i) spec.flange_lengths_mm.push_back(i % 3 == 0 ? 40.0 : 25.0);
  for (int i = 0; i < 11; ++i) {
    spec.bend_angles_deg.push_back(i % 2 == 0 ? 60.0 : -60.0);
    spec.bend_radii_mm.push_back(3.0);
  }
  spec.width_mm = 200.0;
  spec.thickness_mm = 1.5;
  return spec;
}

const std::string& part_file() {
  static const std::string path = [] {
    const auto file = std::filesystem::temp_directory_path() / "springscan_bench_50_faces.step";
    if (!write_profile_cad(fifty_face_profile(), file.string())) std::abort();
    return file.string();
  }();
  return path;
}

void BM_LoadTessellateSample100k(benchmark::State& state) {
  for (auto _ : state) {
    const auto shape = load_cad(part_file());
    const auto samples = sample_cad(*shape, {.sample_count = 100'000});
    benchmark::DoNotOptimize(samples->size());
    state.counters["faces"] = shape->face_count();
    state.counters["triangles"] = shape->report().triangles;
  }
}
BENCHMARK(BM_LoadTessellateSample100k)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->MeasureProcessCPUTime();

// 1M queries scattered within +-2 mm of the surface (a scan after registration), 2 threads.
void BM_Distance1M(benchmark::State& state) {
  const auto shape = load_cad(part_file());
  const auto distance = make_cad_distance(*shape);
  const auto samples = sample_cad(*shape, {.sample_count = 1'000'000, .seed = 2});
  std::mt19937 rng(3);
  std::normal_distribution<double> offset(0.0, 0.7);
  std::vector<Vec3> queries;
  queries.reserve(samples->size());
  for (std::size_t i = 0; i < samples->size(); ++i)
    queries.push_back(samples->points[i] + offset(rng) * samples->normals[i]);
  const int threads = static_cast<int>(state.range(0));
  for (auto _ : state) {
    const auto hits = closest_all(*distance, queries, threads);
    benchmark::DoNotOptimize(hits.data());
  }
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(queries.size()));
}
BENCHMARK(BM_Distance1M)
    ->Arg(1)
    ->Arg(2)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->MeasureProcessCPUTime();

}  // namespace

BENCHMARK_MAIN();
