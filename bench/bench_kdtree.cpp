// KD-tree build and nearest-neighbour queries on scan-sized clouds.
#include <benchmark/benchmark.h>

#include <random>

#include "analysis/core/kdtree.hpp"
#include "tests/analysis/synthetic.hpp"

namespace {

using springscan::analysis::KdTree;
using springscan::analysis::Vec3;
using springscan::analysis::testing::uniform_points;

void BM_KdTreeBuild(benchmark::State& state) {
  const auto points = uniform_points(static_cast<std::size_t>(state.range(0)), 1, -500.0, 500.0);
  for (auto _ : state) {
    KdTree tree(points);
    benchmark::DoNotOptimize(tree.size());
  }
  state.SetItemsProcessed(state.iterations() * state.range(0));
}
BENCHMARK(BM_KdTreeBuild)->Arg(100'000)->Arg(1'000'000)->Unit(benchmark::kMillisecond);

void BM_KdTreeNearest(benchmark::State& state) {
  KdTree tree(uniform_points(static_cast<std::size_t>(state.range(0)), 2, -500.0, 500.0));
  const auto queries = uniform_points(100'000, 3, -500.0, 500.0);
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
