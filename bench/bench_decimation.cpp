// Mesh decimation (paper §2) of a 1M-vertex scanner triangulation: a hat profile sampled on a
// 0.1 mm grid (laser lines across the width), noise sigma 0.01 mm along z, two triangles per
// grid cell. Default settings (target reduction 0.9, max error 0.05 mm, contour kept).
#include <benchmark/benchmark.h>

#include <random>

#include "analysis/preprocess/decimation.hpp"
#include "tests/analysis/grid_mesh.hpp"
#include "tests/analysis/profile_sampling.hpp"

namespace {

using namespace springscan::analysis;

const TriangleMesh& scan_mesh() {
  static const TriangleMesh mesh = [] {
    ProfileSpec spec = hat_profile(25, 30, 40, 90, 3);
    spec.width_mm = 60.0;
    const testing::ProfileSamples grid = testing::sample_profile_spacing(spec, 0.1);
    TriangleMesh m;
    m.vertices = grid.points;
    std::mt19937 rng(5);
    std::normal_distribution<double> noise(0.0, 0.01);
    for (Vec3& p : m.vertices) p.z() += noise(rng);
    const std::size_t columns = static_cast<std::size_t>(grid.last_step) + 1;
    m.triangles = testing::grid_triangles(m.vertices.size() / columns, columns);
    return m;
  }();
  return mesh;
}

void BM_Decimate1M(benchmark::State& state) {
  DecimationSettings settings;
  settings.threads = static_cast<int>(state.range(0));
  const TriangleMesh& mesh = scan_mesh();
  for (auto _ : state) {
    const auto result = decimate_mesh(mesh, settings);
    if (!result) {
      state.SkipWithError(result.message().c_str());
      break;
    }
    state.counters["vertices_in"] = static_cast<double>(mesh.vertices.size());
    state.counters["vertices_out"] = static_cast<double>(result->mesh.vertices.size());
    state.counters["reduction"] = result->achieved_reduction;
    state.counters["max_deviation_mm"] = result->max_deviation_mm;
  }
}
BENCHMARK(BM_Decimate1M)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->Iterations(2);

}  // namespace

BENCHMARK_MAIN();
