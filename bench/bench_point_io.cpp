// Point file reading and writing at scan size: 1M points (a laser line scan of a large part).
// The files are generated once per run into a temporary directory, removed at exit.
#include <benchmark/benchmark.h>

#include <filesystem>
#include <random>

#include "analysis/io/file_io.hpp"
#include "analysis/io/point_io.hpp"

namespace {

namespace fs = std::filesystem;
using springscan::analysis::PlyEncoding;
using springscan::analysis::PointWriteOptions;
using springscan::analysis::Surface;
using springscan::analysis::Vec3;

Surface random_surface(std::size_t n, bool with_normals) {
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> u(-500.0, 500.0);
  Surface s;
  s.cloud.points.resize(n);
  for (auto& p : s.cloud.points) p = Vec3(u(rng), u(rng), u(rng));
  if (with_normals) {
    s.cloud.normals.resize(n);
    for (auto& v : s.cloud.normals) v = Vec3(u(rng), u(rng), u(rng)).normalized();
  }
  return s;
}

// A triangulated grid: two triangles per cell, corners shared as in a scanner's STL.
Surface grid_mesh(std::uint32_t side) {
  Surface s;
  for (std::uint32_t i = 0; i < side; ++i) {
    for (std::uint32_t j = 0; j < side; ++j)
      s.cloud.points.emplace_back(i * 0.5, j * 0.5, 0.01 * i);
  }
  for (std::uint32_t i = 0; i + 1 < side; ++i) {
    for (std::uint32_t j = 0; j + 1 < side; ++j) {
      const std::uint32_t a = i * side + j;
      s.triangles.push_back({a, a + side, a + 1});
      s.triangles.push_back({a + 1, a + side, a + side + 1});
    }
  }
  return s;
}

// The benchmark files, written once; the directory is removed when the program ends.
struct Files {
  fs::path dir = fs::temp_directory_path() /
                 ("springscan_bench_point_io_" + std::to_string(std::random_device{}()));
  std::string ply_binary, ply_ascii, xyz, stl;

  Files() {
    fs::create_directories(dir);
    const Surface cloud = random_surface(1'000'000, true);
    PointWriteOptions binary;
    binary.single_precision = true;  // float xyz + normals, as scanners write them
    PointWriteOptions ascii = binary;
    ascii.ply_encoding = PlyEncoding::kAscii;
    ply_binary = write("scan_binary.ply", cloud, binary);
    ply_ascii = write("scan_ascii.ply", cloud, ascii);
    xyz = write("scan.xyz", cloud, {});
    stl = write("scan.stl", grid_mesh(708), {});  // ~1M triangles
  }
  ~Files() { fs::remove_all(dir); }

  std::string write(const char* name, const Surface& s, const PointWriteOptions& options) {
    const std::string path = (dir / name).string();
    if (!springscan::analysis::write_surface(path, s, options)) std::abort();
    return path;
  }
};

const Files& files() {
  static const Files instance;
  return instance;
}

void read_file(benchmark::State& state, const std::string& path) {
  std::size_t points = 0;
  for (auto _ : state) {
    auto cloud = springscan::analysis::read_point_cloud(path);
    if (!cloud) state.SkipWithError(cloud.message().c_str());
    points = cloud ? cloud->size() : 0;
    benchmark::DoNotOptimize(cloud);
  }
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(points));
  state.SetBytesProcessed(state.iterations() * static_cast<std::int64_t>(fs::file_size(path)));
}

void BM_ReadPlyBinaryFloatXyzNormals1M(benchmark::State& state) {
  read_file(state, files().ply_binary);
}
void BM_ReadPlyAsciiXyzNormals1M(benchmark::State& state) { read_file(state, files().ply_ascii); }
void BM_ReadXyzXyzNormals1M(benchmark::State& state) { read_file(state, files().xyz); }
void BM_ReadStlBinary1MTriangles(benchmark::State& state) { read_file(state, files().stl); }

// Parsing alone, the file already in memory.
void BM_ParsePlyBinaryFloatXyzNormals1M(benchmark::State& state) {
  const std::string bytes = springscan::analysis::read_file_bytes(files().ply_binary).value();
  for (auto _ : state) {
    auto surface = springscan::analysis::parse_ply(bytes, "bench.ply");
    benchmark::DoNotOptimize(surface);
  }
  state.SetItemsProcessed(state.iterations() * 1'000'000);
}

void BM_FormatPlyBinaryDoubleXyzNormals1M(benchmark::State& state) {
  const Surface cloud = random_surface(1'000'000, true);
  for (auto _ : state) {
    auto bytes = springscan::analysis::format_ply(cloud);
    benchmark::DoNotOptimize(bytes);
  }
  state.SetItemsProcessed(state.iterations() * 1'000'000);
}

BENCHMARK(BM_ReadPlyBinaryFloatXyzNormals1M)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ParsePlyBinaryFloatXyzNormals1M)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ReadPlyAsciiXyzNormals1M)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ReadXyzXyzNormals1M)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ReadStlBinary1MTriangles)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_FormatPlyBinaryDoubleXyzNormals1M)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
