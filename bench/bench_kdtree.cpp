// KD-tree build and nearest-neighbour queries on scan-sized clouds.
#include <benchmark/benchmark.h>

#include <random>

#include "analysis/kdtree.hpp"

namespace {

using springscan::analysis::KdTree;
using springscan::analysis::Vec3;

std::vector<Vec3> random_points(std::size_t n, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-500.0, 500.0);
  std::vector<Vec3> points(n);
  for (auto& p : points) p = Vec3(u(rng), u(rng), u(rng));
  return points;
}

void BM_KdTreeBuild(benchmark::State& state) {
  const auto points = random_points(static_cast<std::size_t>(state.range(0)), 1);
  for (auto _ : state) {
    KdTree tree(points);
    benchmark::DoNotOptimize(tree.size());
  }
  state.SetItemsProcessed(state.iterations() * state.range(0));
}
BENCHMARK(BM_KdTreeBuild)->Arg(100'000)->Arg(1'000'000)->Unit(benchmark::kMillisecond);

void BM_KdTreeNearest(benchmark::State& state) {
  KdTree tree(random_points(static_cast<std::size_t>(state.range(0)), 2));
  const auto queries = random_points(100'000, 3);
  for (auto _ : state) {
    double sum = 0.0;
    for (const auto& q : queries) sum += tree.nearest(q)->squared_distance;
    benchmark::DoNotOptimize(sum);
  }
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(queries.size()));
}
BENCHMARK(BM_KdTreeNearest)->Arg(100'000)->Arg(1'000'000)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
