// `springscan match` as a user runs it (docs/performance.md "The whole command", issue 32):
// fork/exec of the real command on point files written once, against the same pairing by
// scipy.optimize.linear_sum_assignment as a whole Python script (bench/reference_scipy.py
// --solve), in the same run. The whole command is timed: program load, reading both files, the
// matching and writing pairs.csv. Budget: scipy / springscan >= 25 at n = 8,192.
//   bench_cli_match [google benchmark flags]   the timings, then the ratio on stdout
//   bench_cli_match --export=DIR               only writes the instances (DIR/<name>_model.xyz,
//                                              DIR/<name>_scan.xyz) and their names, one a line,
//                                              to DIR/instances.txt
#include <benchmark/benchmark.h>
#include <spawn.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <random>
#include <string>
#include <vector>

#include "analysis/preprocess/kcenter.hpp"
#include "bench/kcenter_centers.hpp"
#include "simulators/parts/sheet_profile.hpp"
#include "tests/analysis/profile_sampling.hpp"

extern char** environ;

namespace {

using namespace springscan::analysis;

// The instances, on a hat profile (90 degree bends, r = 2 mm, 120 mm wide) reduced by the
// pipeline's k-center to exactly n centers (bench_matching's surface instances, one size up):
//   surface_<n>_0deg  the scan is the model's own points re-measured with 0.05 mm noise, in
//                     another order (a perfect part: each point's partner is its nearest one);
//   surface_<n>_3deg  the scan is the part sprung open by 3 degrees per bend, sampled and reduced
//                     on its own, with 0.05 mm noise (flange tips displaced by several spacings).

void write_xyz(const std::string& path, const std::vector<Vec3>& points) {
  std::FILE* f = std::fopen(path.c_str(), "w");
  if (f == nullptr) return;
  for (const auto& p : points) std::fprintf(f, "%.17g %.17g %.17g\n", p.x(), p.y(), p.z());
  std::fclose(f);
}

// Writes <name>_model.xyz and <name>_scan.xyz into dir; returns the instance's name.
std::string write_surface_instance(const std::string& dir, std::size_t n, int springback_deg) {
  ProfileSpec nominal = hat_profile(40.0, 40.0, 60.0, 90.0, 2.0);
  nominal.width_mm = 120.0;
  // 0.5 mm spacing: about 100,000 surface samples, so k-center has 8,192 centers to choose.
  const auto model =
      bench::kcenter_centers(testing::sample_profile_spacing(nominal, 0.5).points, n);
  std::vector<Vec3> scan = model;
  std::mt19937 rng(7);
  if (springback_deg == 0) {
    std::shuffle(scan.begin(), scan.end(), rng);
  } else {
    ProfileSpec opened = nominal;
    for (auto& a : opened.bend_angles_deg) a += a > 0 ? -springback_deg : springback_deg;
    scan = bench::kcenter_centers(testing::sample_profile_spacing(opened, 0.5).points, n);
  }
  std::normal_distribution<double> noise(0.0, 0.05);
  for (auto& p : scan) p += Vec3(noise(rng), noise(rng), noise(rng));
  char name[64];
  std::snprintf(name, sizeof name, "surface_%zu_%ddeg", n, springback_deg);
  write_xyz(dir + "/" + name + "_model.xyz", model);
  write_xyz(dir + "/" + name + "_scan.xyz", scan);
  return name;
}

// The instances by (n, springback in degrees): the benchmarks' two arguments.
constexpr std::size_t kSizes[] = {1000, 8192};
constexpr int kSpringbacks[] = {0, 3};

struct Files {
  std::string dir;
  std::map<std::pair<std::size_t, int>, std::string> name;
};

Files& files() {
  static Files f;
  return f;
}

void write_instances(const std::string& dir) {
  files().dir = dir;
  for (const auto n : kSizes) {
    for (const int deg : kSpringbacks) files().name[{n, deg}] = write_surface_instance(dir, n, deg);
  }
}

// Runs argv to completion; returns its exit status (-1 when it could not start or was killed)
// and adds the child's user + system CPU to cpu_ms.
int run_child(const std::vector<std::string>& args, double& cpu_ms) {
  std::vector<char*> argv;
  for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  pid_t pid = 0;
  if (posix_spawn(&pid, argv[0], nullptr, nullptr, argv.data(), environ) != 0) return -1;
  int status = 0;
  rusage usage{};
  if (wait4(pid, &status, 0, &usage) != pid) return -1;
  cpu_ms += 1e3 * static_cast<double>(usage.ru_utime.tv_sec + usage.ru_stime.tv_sec) +
            1e-3 * static_cast<double>(usage.ru_utime.tv_usec + usage.ru_stime.tv_usec);
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

// Sum of the squared distances in a pairs.csv (header, then model,scan,d2 per line).
double total_cost(const std::string& path, std::size_t& pairs) {
  std::ifstream in(path);
  std::string line;
  std::getline(in, line);
  double sum = 0.0;
  pairs = 0;
  while (std::getline(in, line)) {
    const auto comma = line.rfind(',');
    if (comma == std::string::npos) continue;
    sum += std::strtod(line.c_str() + comma + 1, nullptr);
    ++pairs;
  }
  return sum;
}

// Median wall time and mean process CPU (the child's user + system) per command, by tool and
// instance: the ratios printed at the end. CPU is what an idle station pays when this machine is
// loaded.
struct Timing {
  double wall_ms = 0.0;
  double cpu_ms = 0.0;
};

std::map<std::pair<std::string, std::string>, Timing>& medians() {
  static std::map<std::pair<std::string, std::string>, Timing> m;
  return m;
}

const std::string& instance_name(const benchmark::State& state) {
  return files().name.at({static_cast<std::size_t>(state.range(0)), state.range(1)});
}

void time_command(benchmark::State& state, const std::string& tool,
                  const std::vector<std::string>& args, const std::string& out) {
  const auto n = static_cast<std::size_t>(state.range(0));
  std::vector<double> wall_ms;
  double cpu_ms = 0.0;
  for (auto _ : state) {
    const auto start = std::chrono::steady_clock::now();
    const int status = run_child(args, cpu_ms);
    wall_ms.push_back(
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
            .count());
    if (status != 0) {
      state.SkipWithError((tool + " exited with " + std::to_string(status)).c_str());
      return;
    }
  }
  std::sort(wall_ms.begin(), wall_ms.end());
  const double mean_cpu_ms = cpu_ms / static_cast<double>(state.iterations());
  medians()[{tool, instance_name(state)}] = {wall_ms[wall_ms.size() / 2], mean_cpu_ms};
  std::size_t pairs = 0;
  state.counters["cost_mm2"] = total_cost(out, pairs);
  state.counters["pairs"] = static_cast<double>(pairs);
  state.counters["child_cpu_ms"] = mean_cpu_ms;
  if (pairs != n) state.SkipWithError("pairs.csv does not hold n pairs");
}

std::string instance_path(const benchmark::State& state, const char* which) {
  return files().dir + "/" + instance_name(state) + "_" + which + ".xyz";
}

void BM_SpringscanMatch(benchmark::State& state) {
  const std::string out = files().dir + "/springscan_pairs.csv";
  time_command(state, "springscan",
               {SPRINGSCAN_EXECUTABLE, "match", "--model", instance_path(state, "model"), "--scan",
                instance_path(state, "scan"), "--out", out, "--quiet"},
               out);
}

void BM_ScipyScript(benchmark::State& state) {
  const std::string out = files().dir + "/scipy_pairs.csv";
  time_command(state, "scipy",
               {"/usr/bin/python3", SPRINGSCAN_REFERENCE_SCIPY, "--solve",
                instance_path(state, "model"), instance_path(state, "scan"), out},
               out);
}

// Arguments: n, springback in degrees.
BENCHMARK(BM_SpringscanMatch)
    ->ArgsProduct({{1000, 8192}, {0, 3}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
// Up to 20 s per run at n = 8,192 (the dense solver on a displaced scan): three runs for a median.
BENCHMARK(BM_ScipyScript)
    ->ArgsProduct({{1000}, {0, 3}})
    ->Iterations(5)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK(BM_ScipyScript)
    ->ArgsProduct({{8192}, {0, 3}})
    ->Iterations(3)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

int export_instances(const std::string& dir) {
  write_instances(dir);
  std::ofstream list(dir + "/instances.txt");
  for (const auto& [key, name] : files().name) list << name << '\n';
  return list ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
  for (int i = 1; i < argc; ++i) {
    if (std::strncmp(argv[i], "--export=", 9) == 0) return export_instances(argv[i] + 9);
  }
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  char tmp[] = "/tmp/bench_cli_match_XXXXXX";
  if (mkdtemp(tmp) == nullptr) return 1;
  write_instances(tmp);
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  for (const auto& [key, name] : files().name) {
    const auto ours = medians().find({"springscan", name});
    const auto scipy = medians().find({"scipy", name});
    if (ours == medians().end() || scipy == medians().end()) continue;
    const Timing& a = ours->second;
    const Timing& b = scipy->second;
    std::printf(
        "%s: springscan match %.1f ms wall / %.1f ms CPU, scipy script %.1f / %.1f ms: "
        "%.1fx wall, %.1fx CPU\n",
        name.c_str(), a.wall_ms, a.cpu_ms, b.wall_ms, b.cpu_ms, b.wall_ms / a.wall_ms,
        b.cpu_ms / a.cpu_ms);
  }
  std::filesystem::remove_all(tmp);
  return 0;
}
