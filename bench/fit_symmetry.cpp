// Figures program (not a test): how often the global fit picks the right orientation of a
// near-symmetric part. Trials cycle over hats whose last brim is longer by 3, 4 or
// 5 mm (8,000-point scans) and two openamr parts laser-scanned from one side (15,000 points),
// all with sigma = 0.02 mm noise, under poses near a half turn about each part axis (off by up
// to 10 degrees, up to 200 mm away). A trial is right when the fit ends within 1 degree of the
// true rotation (distinct orientations are 5 degrees or more apart) and is not called
// ambiguous. Usage: fit_symmetry [trials] (default 200)
#include <cstdio>
#include <cstdlib>
#include <numbers>
#include <random>
#include <string>

#include "analysis/registration/global_fit.hpp"
#include "simulators/parts/laser_scan.hpp"
#include "simulators/parts/produced_part.hpp"
#include "simulators/parts/sheet_part.hpp"
#include "tests/analysis/synthetic.hpp"
#include "tests/support/test_paths.hpp"

namespace {

using namespace springscan::analysis;
namespace parts = springscan::parts;
constexpr double kDeg = std::numbers::pi / 180.0;

Transform near_half_turn(std::mt19937& rng, int axis) {
  std::normal_distribution<double> g;
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const Vec3 wobble = Vec3(g(rng), g(rng), g(rng)).normalized();
  Transform T = Transform::Identity();
  T.linear() = Eigen::AngleAxisd(10.0 * kDeg * u(rng), wobble).toRotationMatrix() *
               Eigen::AngleAxisd(std::numbers::pi, Vec3::Unit(axis)).toRotationMatrix();
  T.translation() = 200.0 * Vec3(u(rng), u(rng), u(rng));
  return T;
}

struct Case {
  std::string name;
  PointCloud model;
  std::unique_ptr<KdTree> tree;
  ProfileSpec spec;                           // hats
  std::unique_ptr<parts::ProducedPart> part;  // openamr parts
};

}  // namespace

int main(int argc, char** argv) {
  const int trials = argc > 1 ? std::atoi(argv[1]) : 200;
  std::vector<Case> cases;
  for (double extra : {3.0, 4.0, 5.0}) {
    Case c;
    c.name = "hat +" + std::to_string(static_cast<int>(extra)) + " mm";
    c.spec = hat_profile(25, 30, 40, 60, 4);
    c.spec.width_mm = 80;
    c.spec.flange_lengths_mm.back() += extra;
    c.model = testing::sample_profile(c.spec, 40000, 7);
    c.tree = std::make_unique<KdTree>(c.model.points);
    cases.push_back(std::move(c));
  }
  for (const char* file : {"openamr-MMP.03.00.00.003_Motor_bracket.step",
                           "openamr-MMP.01.00.00.002_Cover_flange.step"}) {
    auto loaded = parts::load_cad_part(springscan::test_paths::shared_cad(file));
    if (!loaded) return std::fprintf(stderr, "%s: %s\n", file, loaded.message().c_str()), 1;
    const std::vector<double> sb(loaded->model.segmentation.bends.size(), 0.0);
    auto part = parts::make_produced_part(loaded->model, loaded->shape, sb);
    if (!part) return std::fprintf(stderr, "%s: %s\n", file, part.message().c_str()), 1;
    Case c;
    c.name = file;
    c.model = loaded->model.samples;
    c.tree = std::make_unique<KdTree>(c.model.points);
    c.part = std::make_unique<parts::ProducedPart>(std::move(*part));
    cases.push_back(std::move(c));
  }
  std::mt19937 rng(2026);
  std::vector<int> right(cases.size(), 0), total(cases.size(), 0), ambiguous(cases.size(), 0);
  GlobalFitSettings settings;
  settings.icp.max_iterations = 30;
  for (int t = 0; t < trials; ++t) {
    const std::size_t k = static_cast<std::size_t>(t) % cases.size();
    Case& c = cases[k];
    const Transform T_scan_part = near_half_turn(rng, (t / static_cast<int>(cases.size())) % 3);
    std::vector<Vec3> scan;
    if (c.part) {
      parts::LaserScanSettings st;
      st.point_count = 15000;
      st.noise_sigma_mm = 0.02;
      st.T_scan_part = T_scan_part;
      st.seed = static_cast<std::uint64_t>(t + 1);
      auto s = parts::laser_scan(*c.part, st);
      if (!s) return std::fprintf(stderr, "scan: %s\n", s.message().c_str()), 1;
      scan = std::move(s->cloud.points);
    } else {
      ScanSimulationSettings st;
      st.point_count = 8000;
      st.noise_sigma_mm = 0.02;
      st.T_scan_part = T_scan_part;
      st.seed = static_cast<std::uint64_t>(t + 1);
      auto s = simulate_scan(c.spec, std::vector<double>(4, 0.0), st);
      if (!s) return std::fprintf(stderr, "scan: %s\n", s.message().c_str()), 1;
      scan = std::move(s->points);
    }
    auto fit = global_fit(scan, *c.tree, c.model.normals, settings);
    ++total[k];
    if (!fit) continue;
    const double err =
        Eigen::AngleAxisd(fit->T_cad_scan.linear() * T_scan_part.linear()).angle() / kDeg;
    if (fit->ambiguous) ++ambiguous[k];
    if (err < 1.0 && !fit->ambiguous)
      ++right[k];
    else
      std::printf("miss: trial %d %s axis %d: %.2f deg off, ratio %.3f, %zu finalists\n", t,
                  c.name.c_str(), (t / static_cast<int>(cases.size())) % 3, err,
                  fit->orientation.ambiguity, fit->orientation.candidates.size());
  }
  int all_right = 0, all = 0;
  for (std::size_t k = 0; k < cases.size(); ++k) {
    std::printf("%-48s right %3d / %3d  ambiguous %d\n", cases[k].name.c_str(), right[k], total[k],
                ambiguous[k]);
    all_right += right[k];
    all += total[k];
  }
  std::printf("all: right %d / %d\n", all_right, all);
  return 0;
}
