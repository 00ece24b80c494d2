// Minimum-cost matching (speed targets in docs/performance.md): dense n = 1,000 and sparse n =
// 4,096 points of k-center-reduced sheet surfaces.
//   bench_matching [google benchmark flags]      the timings
//   bench_matching --export=DIR                  writes the instances, our costs and median
//                                                times for bench/reference_scipy.py
#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <fstream>
#include <functional>
#include <memory>
#include <random>
#include <string>

#include "analysis/matching/assignment_points.hpp"
#include "analysis/preprocess/kcenter.hpp"
#include "bench/kcenter_centers.hpp"
#include "simulators/parts/sheet_profile.hpp"
#include "tests/analysis/profile_sampling.hpp"
#include "tests/analysis/synthetic.hpp"

namespace {

using namespace springscan::analysis;

// A hat profile (the paper's part family), its scan bent open by 3 degrees per bend with
// 0.05 mm noise, both reduced to n centers: the inputs the pipeline hands to the matching.
struct Instance {
  std::string name;
  std::vector<Vec3> model;
  std::vector<Vec3> scan;
};

Instance surface_instance(std::size_t n, double springback_deg = 3.0) {
  ProfileSpec nominal = hat_profile(40.0, 40.0, 60.0, 90.0, 2.0);
  nominal.width_mm = 120.0;
  ProfileSpec opened = nominal;
  for (auto& a : opened.bend_angles_deg) a += a > 0 ? -springback_deg : springback_deg;
  auto model = testing::sample_profile_spacing(nominal, 0.8).points;
  auto scan = testing::sample_profile_spacing(opened, 0.8).points;
  std::mt19937 rng(7);
  std::normal_distribution<double> noise(0.0, 0.05);
  for (auto& p : scan) p += Vec3(noise(rng), noise(rng), noise(rng));
  char name[64];
  if (springback_deg == 3.0) {
    std::snprintf(name, sizeof name, "surface_%zu", n);
  } else {
    std::snprintf(name, sizeof name, "surface_%zu_%gdeg", n, springback_deg);
  }
  return {name, bench::kcenter_centers(model, n), bench::kcenter_centers(scan, n)};
}

Instance random_instance(std::size_t n) {
  return {"random_" + std::to_string(n), testing::uniform_points(n, 1),
          testing::uniform_points(n, 2)};
}

const Instance& cached(const std::function<Instance()>& make, int which) {
  static std::vector<std::unique_ptr<Instance>> cache(8);
  if (!cache[static_cast<std::size_t>(which)]) {
    cache[static_cast<std::size_t>(which)] = std::make_unique<Instance>(make());
  }
  return *cache[static_cast<std::size_t>(which)];
}

const Instance& random_1000() {
  return cached([] { return random_instance(1000); }, 0);
}
const Instance& surface_1000() {
  return cached([] { return surface_instance(1000); }, 1);
}
const Instance& surface_4096() {
  return cached([] { return surface_instance(4096); }, 2);
}
// A large deformation: 8 degrees of springback per bend moves the flange tips by several point
// spacings, so the k = 32 candidate graph has no perfect matching and k is widened.
const Instance& surface_4096_8deg() {
  return cached([] { return surface_instance(4096, 8.0); }, 3);
}

void run(benchmark::State& state, const Instance& inst, const PointMatchingSettings& s) {
  PointMatching last;
  for (auto _ : state) {
    auto m = match_points(inst.model, inst.scan, s);
    if (!m.ok() || !m->certified) {
      state.SkipWithError("matching failed or not certified");
      return;
    }
    last = std::move(m).value();
  }
  state.counters["cost_mm2"] = last.total_cost;
  state.counters["k"] = last.candidate_neighbors;  // final k of the candidate graph (sparse)
  state.counters["pricing"] = last.pricing_rounds;
  state.counters["dense"] = last.used_dense;
}

constexpr PointMatchingSettings kDense{.dense_limit = 1'000'000};
constexpr PointMatchingSettings kSparse{.dense_limit = 0};

void BM_DenseRandom1000(benchmark::State& st) { run(st, random_1000(), kDense); }
void BM_DenseSurface1000(benchmark::State& st) { run(st, surface_1000(), kDense); }
void BM_SparseSurface1000(benchmark::State& st) { run(st, surface_1000(), kSparse); }
void BM_SparseSurface4096(benchmark::State& st) { run(st, surface_4096(), kSparse); }
void BM_DenseSurface4096(benchmark::State& st) { run(st, surface_4096(), kDense); }
void BM_SparseSurface4096Springback8(benchmark::State& st) {
  run(st, surface_4096_8deg(), kSparse);
}
BENCHMARK(BM_DenseRandom1000)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_DenseSurface1000)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_SparseSurface1000)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_SparseSurface4096)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_DenseSurface4096)->Unit(benchmark::kMillisecond)->Iterations(3);
BENCHMARK(BM_SparseSurface4096Springback8)->Unit(benchmark::kMillisecond);

void write_points(const std::string& path, const std::vector<Vec3>& points) {
  std::FILE* f = std::fopen(path.c_str(), "w");
  if (f == nullptr) return;
  for (const auto& p : points) std::fprintf(f, "%.17g %.17g %.17g\n", p.x(), p.y(), p.z());
  std::fclose(f);
}

double process_cpu_ms() {
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return 1e3 * static_cast<double>(t.tv_sec) + 1e-6 * static_cast<double>(t.tv_nsec);
}

// Writes each instance and one line "name solver cost_mm2 median_wall_ms median_cpu_ms" per
// solver run (process CPU time: what an idle machine pays when this one is loaded).
int export_instances(const std::string& dir) {
  std::ofstream summary(dir + "/ours.txt");
  const std::pair<const Instance*, std::pair<const char*, PointMatchingSettings>> runs[] = {
      {&random_1000(), {"dense", kDense}},
      {&surface_1000(), {"dense", kDense}},
      {&surface_1000(), {"sparse", kSparse}},
      {&surface_4096(), {"sparse", kSparse}}};
  for (const auto& [inst, solver] : runs) {
    write_points(dir + "/" + inst->name + "_model.txt", inst->model);
    write_points(dir + "/" + inst->name + "_scan.txt", inst->scan);
    std::vector<double> wall_ms, cpu_ms;
    double cost = 0.0;
    for (int rep = 0; rep < 9; ++rep) {
      const double cpu0 = process_cpu_ms();
      const auto t0 = std::chrono::steady_clock::now();
      const auto m = match_points(inst->model, inst->scan, solver.second);
      wall_ms.push_back(
          std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
      cpu_ms.push_back(process_cpu_ms() - cpu0);
      if (!m.ok() || !m->certified) return 1;
      cost = m->total_cost;
    }
    std::sort(wall_ms.begin(), wall_ms.end());
    std::sort(cpu_ms.begin(), cpu_ms.end());
    char line[256];
    std::snprintf(line, sizeof line, "%s %s %.17g %.4f %.4f\n", inst->name.c_str(), solver.first,
                  cost, wall_ms[wall_ms.size() / 2], cpu_ms[cpu_ms.size() / 2]);
    summary << line;
  }
  return summary ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
  for (int i = 1; i < argc; ++i) {
    if (std::strncmp(argv[i], "--export=", 9) == 0) return export_instances(argv[i] + 9);
  }
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
