// Scanner data path on one core: frame decoding (magic search, CRC-32, header) plus payload
// decoding and conversion to part coordinates, over a byte stream as it arrives from USB.
#include <benchmark/benchmark.h>

#include <cmath>
#include <random>

#include "drivers/codec.hpp"
#include "drivers/conversion.hpp"
#include "drivers/messages.hpp"

namespace {

namespace d = springscan::drivers;
namespace p = springscan::drivers::protocol;

// A laser scan: `profiles` frames of `points` points each, as the device sends them.
std::vector<std::uint8_t> laser_stream(std::size_t profiles, std::size_t points) {
  std::mt19937 rng(3);
  std::normal_distribution<float> noise(0.0f, 0.02f);
  std::vector<std::uint8_t> stream;
  std::vector<d::SensorPoint> line(points);
  for (std::size_t k = 0; k < profiles; ++k) {
    for (std::size_t i = 0; i < points; ++i)
      line[i] = {float(i) * 0.1f - 100.0f, 180.0f + noise(rng)};
    const auto payload =
        d::encode_laser_profile(static_cast<std::uint32_t>(k), double(k) * 0.5, k * 1000, line);
    d::append_frame(stream, p::MessageType::kLaserProfile, static_cast<std::uint32_t>(k), payload);
  }
  return stream;
}

std::vector<std::uint8_t> probe_stream(std::size_t frames) {
  std::vector<std::uint8_t> stream;
  std::vector<d::ProbeRecord> records(p::kMaxProbeRecords);
  for (std::size_t i = 0; i < records.size(); ++i)
    records[i] = {{double(i), 2.0 * double(i), 30.0}, {0.0f, 0.0f, -1.0f}, 1.5f};
  for (std::size_t k = 0; k < frames; ++k) {
    const auto payload =
        d::encode_probe_batch(static_cast<std::uint32_t>(k * records.size()), 0, records);
    d::append_frame(stream, p::MessageType::kProbePoints, static_cast<std::uint32_t>(k), payload);
  }
  return stream;
}

// Feeds the stream in 16 KiB USB transfers and converts every profile, as the driver does.
void BM_LaserDecodeAndConvert(benchmark::State& state) {
  const auto points = static_cast<std::size_t>(state.range(0));
  const std::size_t profiles = 2000;
  const auto stream = laser_stream(profiles, points);
  const d::LaserCalibration calibration;
  std::vector<springscan::analysis::Vec3> cloud;
  cloud.reserve(profiles * points);
  for (auto _ : state) {
    cloud.clear();
    d::FrameDecoder decoder;
    d::SequenceChecker sequence;
    d::FrameView frame;
    for (std::size_t at = 0; at < stream.size(); at += 16384) {
      decoder.feed(std::span(stream).subspan(at, std::min<std::size_t>(16384, stream.size() - at)));
      while (decoder.next(frame) == d::DecodeStatus::kFrame) {
        sequence.check(frame.header.sequence);
        const auto profile = d::decode_laser_profile(frame.payload);
        d::append_laser_profile(*profile, calibration, cloud);
      }
    }
    benchmark::DoNotOptimize(cloud.data());
  }
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(profiles * points));
  state.SetBytesProcessed(state.iterations() * static_cast<std::int64_t>(stream.size()));
}
BENCHMARK(BM_LaserDecodeAndConvert)->Arg(1024)->Arg(4096)->Unit(benchmark::kMillisecond);

void BM_ProbeDecodeAndConvert(benchmark::State& state) {
  const std::size_t frames = 500;
  const auto stream = probe_stream(frames);
  const d::ProbeCalibration calibration;
  std::vector<springscan::analysis::Vec3> cloud, normals;
  cloud.reserve(frames * p::kMaxProbeRecords);
  normals.reserve(frames * p::kMaxProbeRecords);
  for (auto _ : state) {
    cloud.clear();
    normals.clear();
    d::FrameDecoder decoder;
    d::FrameView frame;
    decoder.feed(stream);
    while (decoder.next(frame) == d::DecodeStatus::kFrame) {
      const auto batch = d::decode_probe_batch(frame.payload);
      d::append_probe_batch(*batch, calibration, cloud, &normals);
    }
    benchmark::DoNotOptimize(cloud.data());
  }
  state.SetItemsProcessed(state.iterations() *
                          static_cast<std::int64_t>(frames * p::kMaxProbeRecords));
}
BENCHMARK(BM_ProbeDecodeAndConvert)->Unit(benchmark::kMillisecond);

void BM_Crc32(benchmark::State& state) {
  const auto stream = laser_stream(64, 4096);
  for (auto _ : state) benchmark::DoNotOptimize(d::crc32(stream));
  state.SetBytesProcessed(state.iterations() * static_cast<std::int64_t>(stream.size()));
}
BENCHMARK(BM_Crc32);

}  // namespace
BENCHMARK_MAIN();
