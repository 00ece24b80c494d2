// `springscan trend` over 10,000 reports (its budget: <= 2 s): reading a report store of
// station-sized report.pb files (bends, deviation, a deformation field and compensation
// vectors, about 15 kB each, like the HIL station's), the statistics, and the page. The store
// is written once into a temp directory and removed at exit.
#include <benchmark/benchmark.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <random>

#include "report/trend.hpp"
#include "report/trend_html.hpp"

namespace {

namespace fs = std::filesystem;
using namespace springscan;

v1::InspectionReport station_report(int k, std::mt19937& rng) {
  std::normal_distribution<double> noise(0.0, 1.0);
  v1::InspectionReport r;
  r.set_schema("springscan.report.v1");
  r.set_software_version("0.1.0");
  char utc[32];
  std::snprintf(utc, sizeof utc, "2026-12-%02dT%02d:%02d:%02dZ", 1 + k / 86400, (k / 3600) % 24,
                (k / 60) % 60, k % 60);
  r.set_created_utc(utc);
  r.set_station("press-4");
  r.set_job_id(k);
  r.set_result_seq(static_cast<std::uint32_t>(k % 65535 + 1));
  r.mutable_input()->set_part_id(std::to_string(1 + k % 2));
  r.mutable_input()->set_cad_file("/etc/springscan/parts/hat-profile.step");
  for (int b = 0; b < 4; ++b) {
    v1::Bend* bend = r.add_bends();
    bend->set_id(b + 1);
    bend->set_measured(true);
    bend->set_nominal_angle_deg(90.0);
    bend->set_springback_deg(0.4 + 0.1 * b + 0.08 * noise(rng) + (k % 500 > 480 ? 0.3 : 0.0));
    bend->set_measured_angle_deg(90.0 - bend->springback_deg());
    bend->set_angle_tolerance_deg(1.0);
    bend->set_pass(true);
    for (int f = 0; f < 3; ++f) bend->add_cad_faces(b * 3 + f);
  }
  v1::Deviation* d = r.mutable_deviation();
  d->set_points(16000);
  d->set_tolerance_mm(0.5);
  d->set_p95(0.12 + 0.01 * noise(rng));
  d->set_max(0.25 + 0.02 * noise(rng));
  d->set_min(-0.2);
  d->set_rms(0.06);
  v1::DeformationField* field = r.mutable_deformation_field();
  field->set_method("min_cost_matching");
  for (int v = 0; v < 200; ++v) {
    v1::Correspondence* c = field->add_vectors();
    c->mutable_model()->set_x(noise(rng));
    c->mutable_model()->set_y(noise(rng));
    c->mutable_model()->set_z(noise(rng));
    c->mutable_scan()->set_x(noise(rng));
    c->mutable_scan()->set_y(noise(rng));
    c->mutable_scan()->set_z(noise(rng));
    c->set_model_index(v);
    c->set_scan_index(v);
    c->set_squared_distance(0.01);
  }
  for (int v = 0; v < 60; ++v) {
    v1::CompensationVector* c = r.add_compensation();
    c->mutable_point()->set_x(noise(rng));
    c->mutable_vector()->set_z(0.01 * noise(rng));
  }
  return r;
}

/// A report store of `n` records in a temp directory, written on first use.
const std::string& store(int n) {
  static const std::string dir = [n] {
    const fs::path d =
        fs::temp_directory_path() / ("springscan_bench_trend_" + std::to_string(::getpid()));
    std::mt19937 rng(7);
    std::size_t bytes = 0;
    for (int k = 1; k <= n; ++k) {
      char name[32];
      std::snprintf(name, sizeof name, "r%012d", k);
      fs::create_directories(d / name);
      const std::string pb = station_report(k, rng).SerializeAsString();
      bytes += pb.size();
      std::ofstream(d / name / "report.pb", std::ios::binary) << pb;
    }
    std::fprintf(stderr, "bench_trend: %d reports, %.1f kB each, in %s\n", n,
                 static_cast<double>(bytes) / n / 1e3, d.c_str());
    std::atexit([] {
      fs::remove_all(fs::temp_directory_path() /
                     ("springscan_bench_trend_" + std::to_string(::getpid())));
    });
    return d.string();
  }();
  return dir;
}

void BM_TrendWholeCommand(benchmark::State& state) {
  const std::string& dir = store(static_cast<int>(state.range(0)));
  std::size_t html_bytes = 0;
  for (auto _ : state) {
    auto input = report::read_reports({dir});
    if (!input) state.SkipWithError(input.message().c_str());
    const auto cs = report::collect_characteristics(input->reports);
    report::TrendPageInfo info;
    info.reports = input->reports.size();
    const std::string html = report::render_trend_html(cs, info);
    html_bytes = html.size();
    benchmark::DoNotOptimize(html.data());
  }
  state.counters["html_MB"] = static_cast<double>(html_bytes) / 1e6;
}
BENCHMARK(BM_TrendWholeCommand)
    ->Arg(10'000)
    ->MeasureProcessCPUTime()
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);

void BM_TrendStatisticsAndPage(benchmark::State& state) {
  const std::string& dir = store(static_cast<int>(state.range(0)));
  auto input = report::read_reports({dir});
  for (auto _ : state) {
    const auto cs = report::collect_characteristics(input->reports);
    report::TrendPageInfo info;
    const std::string html = report::render_trend_html(cs, info);
    benchmark::DoNotOptimize(html.data());
  }
}
BENCHMARK(BM_TrendStatisticsAndPage)->Arg(10'000)->UseRealTime()->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
