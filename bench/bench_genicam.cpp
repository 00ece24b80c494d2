// The GenICam driver's data path (docs/performance.md, "GenICam profilers"): range lines to part
// coordinates alone, and whole scans from the simulated profiler over GigE Vision on loopback
// (Aravis's fake camera filling frames, GVSP over UDP, the driver's stream and conversion).
// One GenICam camera per machine (port 3956): do not run two of these at once.
#include <benchmark/benchmark.h>

#include <cmath>
#include <random>

#include "drivers/genicam/genicam_scanner.hpp"
#include "simulators/genicam_camera.hpp"

namespace {

namespace g = springscan::drivers::genicam;

// Converting Coord3D_C16 frames of 64 lines, `width` points a line, 5 % missing.
void BM_GenicamConvertC16(benchmark::State& state) {
  const auto width = static_cast<std::uint32_t>(state.range(0));
  const std::uint32_t height = 64;
  std::mt19937 rng(5);
  std::uniform_int_distribution<int> raw(0, 65535);
  std::vector<std::uint8_t> bytes(std::size_t(width) * height * 2);
  for (std::size_t k = 0; k < bytes.size(); k += 2) {
    const int v = raw(rng) % 20 == 0 ? 0 : raw(rng);
    bytes[k] = static_cast<std::uint8_t>(v & 0xFF);
    bytes[k + 1] = static_cast<std::uint8_t>(v >> 8);
  }
  g::RangeScaling scaling;
  scaling.a = {0.05, -50.0};
  scaling.c = {0.004, 60.0, true, 0.0};
  const springscan::drivers::LaserCalibration calibration;
  std::vector<springscan::analysis::Vec3> out;
  out.reserve(std::size_t(width) * height);
  std::int64_t line = 0;
  for (auto _ : state) {
    out.clear();
    const g::RangeFrameView frame{
        g::RangeFormat::kCoord3dC16, bytes.data(), bytes.size(), width, height, line};
    benchmark::DoNotOptimize(g::append_range_lines(frame, scaling, calibration, 0.1, out));
    line += height;
  }
  state.SetItemsProcessed(state.iterations() * height);  // lines
  state.counters["points/s"] =
      benchmark::Counter(double(state.iterations()) * width * height, benchmark::Counter::kIsRate);
}
BENCHMARK(BM_GenicamConvertC16)->Arg(1024)->Arg(2048);

// Whole scans through the driver from the simulated profiler on 127.0.0.1: `width` points a
// line, 64 lines a frame, a frame every `period` us (the fake camera's pacing).
void BM_GenicamLoopbackScan(benchmark::State& state) {
  const int width = static_cast<int>(state.range(0));
  const int period_us = static_cast<int>(state.range(1));
  springscan::simulators::RangeImage image;
  image.width = width;
  image.lines = 64;
  image.dx_mm = 0.05;
  for (int k = 0; k < image.width * image.lines; ++k)
    image.range_mm.push_back(float(150.0 + 10.0 * std::sin(k * 0.01)));
  springscan::simulators::GenicamCameraSettings camera;
  camera.frame_period_us = period_us;
  camera.lines_per_frame = 64;
  auto running = springscan::simulators::GenicamCamera::start(camera, image);
  if (!running) {
    state.SkipWithError(running.message().c_str());
    return;
  }
  g::GenicamSettings settings;
  settings.camera_id = "127.0.0.1";
  settings.line_step_mm = 0.1;
  settings.lines_per_frame = 64;
  settings.scan_lines = 64 * 100;
  settings.max_lost_frames = 1000000;  // counted, not failed: loss is part of the figure
  g::GenicamScanner scanner(settings);
  std::int64_t lines = 0, lost = 0;
  for (auto _ : state) {
    auto cloud = scanner.scan({});
    if (!cloud) {
      state.SkipWithError(cloud.message().c_str());
      return;
    }
    lines += scanner.last_outcome().lines;
    lost += scanner.last_outcome().lost_frames;
  }
  state.SetItemsProcessed(lines);  // lines
  state.counters["offered_lines/s"] = 64e6 / period_us;
  state.counters["lost_frames"] = double(lost);
}
BENCHMARK(BM_GenicamLoopbackScan)
    ->ArgsProduct({{1024, 2048}, {4000, 2000, 1000, 500}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Iterations(5);

}  // namespace

BENCHMARK_MAIN();
