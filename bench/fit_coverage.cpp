// Figures program (not a test): how often the global fit (PCA candidates + ICP) lands on the
// right pose when the scan sees only part of the part. For each profile and coverage, random
// rigid motions (any rotation, up to 300 mm) of a 30k-point scan covering a stretch of the
// profile (sigma 0.02 mm noise, 1 % outliers), fitted as the pipeline does (voxel centroids,
// box diagonal / 150) against 100k model samples; a trial succeeds when 95 % of the fitted scan
// points lie within 0.1 mm of the model surface. Usage: fit_coverage [trials per row]
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <random>
#include <string>

#include "analysis/preprocess/reduction.hpp"
#include "analysis/preprocess/voxel.hpp"
#include "analysis/registration/global_fit.hpp"
#include "tests/analysis/synthetic.hpp"

namespace {

using namespace springscan::analysis;

struct Part {
  std::string name;
  ProfileSpec spec;
};

std::vector<Part> parts() {
  std::vector<Part> out;
  ProfileSpec four;
  four.flange_lengths_mm = {80, 60, 120, 40};
  four.bend_angles_deg = {90, -60, 45};
  four.bend_radii_mm = {5, 8, 6};
  four.width_mm = 200;
  out.push_back({"four-flange", four});
  ProfileSpec hat;
  hat.flange_lengths_mm = {25, 30, 40, 30, 25};
  hat.bend_angles_deg = {60, -60, -60, 60};
  hat.bend_radii_mm = {4, 4, 4, 4};
  hat.width_mm = 80;
  out.push_back({"hat", hat});
  ProfileSpec ell;
  ell.flange_lengths_mm = {80, 50};
  ell.bend_angles_deg = {90};
  ell.bend_radii_mm = {5};
  ell.width_mm = 60;
  out.push_back({"L", ell});
  return out;
}

double surface_p95(const std::vector<Vec3>& scan, const Transform& T, const KdTree& tree,
                   const std::vector<Vec3>& normals) {
  std::vector<double> d;
  d.reserve(scan.size());
  for (const auto& p : scan) {
    const Vec3 q = T * p;
    const auto n = tree.nearest(q);
    d.push_back(std::abs(normals[n->index].dot(q - tree.points()[n->index])) +
                std::max(0.0, std::sqrt(n->squared_distance) - 5.0));  // off the model's end
  }
  std::nth_element(d.begin(), d.begin() + static_cast<std::ptrdiff_t>(0.95 * d.size()), d.end());
  return d[static_cast<std::size_t>(0.95 * d.size())];
}

}  // namespace

int main(int argc, char** argv) {
  const int trials = argc > 1 ? std::stoi(argv[1]) : 20;
  const double coverages[] = {1.0, 0.8, 0.7, 0.6, 0.5, 0.4};
  std::printf("%-12s %-9s %-8s %s\n", "part", "coverage", "ok", "median CPU ms");
  for (const Part& part : parts()) {
    const PointCloud model = testing::sample_profile(part.spec, 100'000, 1);
    const KdTree tree(model.points);
    for (double c : coverages) {
      int ok = 0;
      std::vector<double> ms;
      std::mt19937 rng(7);
      std::uniform_real_distribution<double> u(0.0, 1.0);
      for (int t = 0; t < trials; ++t) {
        const double from = (1.0 - c) * u(rng);
        PointCloud scan = testing::sample_profile(part.spec, 30'000, 100 + t, from, from + c);
        const Transform motion = testing::random_motion(rng, 300.0);
        for (auto& p : scan.points) p = motion * p;
        testing::add_noise(scan.points, 0.02, 200 + t);
        testing::add_outliers(scan.points, 0.01, 5.0, 300 + t);
        // As the pipeline does: the fit runs on voxel centroids (box diagonal / 150).
        const auto [lo, hi] = bounding_box(scan.points);
        const auto fit_points = voxel_reduce(scan, {(hi - lo).norm() / 150.0})->cloud.points;
        const std::clock_t t0 = std::clock();  // process CPU time, all threads
        auto fit = global_fit(fit_points, tree, model.normals);
        ms.push_back(1000.0 * static_cast<double>(std::clock() - t0) / CLOCKS_PER_SEC);
        const bool good =
            fit && surface_p95(scan.points, fit->T_cad_scan, tree, model.normals) < 0.1;
        if (good) ++ok;
        if (!good && std::getenv("DIAG")) {
          // Oracle: the true rotation, centroids aligned, then ICP.
          const Transform truth = motion.inverse();
          auto sf = principal_frame(scan.points);
          auto mf = principal_frame(model.points);
          Transform start = Transform::Identity();
          start.linear() = truth.linear();
          start.translation() = mf->centroid - truth.linear() * sf->centroid;
          GlobalFitSettings s;
          s.pca_initial_alignment = false;
          std::vector<Vec3> moved;
          for (auto& p : scan.points) moved.push_back(start * p);
          auto f2 = global_fit(moved, tree, model.normals, s);
          const double r = f2 ? surface_p95(moved, f2->T_cad_scan, tree, model.normals) : -1;
          std::printf(
              "   fail trial %d from %.2f: p95 %.2f ambiguity %.3f best %zu; oracle-rotation p95 "
              "%.3f\n",
              t, from, fit ? surface_p95(scan.points, fit->T_cad_scan, tree, model.normals) : -1.0,
              fit ? fit->pca.ambiguity : 0.0, fit ? fit->pca.best_candidate : 0, r);
        }
      }
      std::sort(ms.begin(), ms.end());
      std::printf("%-12s %-9.2f %3d/%-4d %.0f\n", part.name.c_str(), c, ok, trials,
                  ms[ms.size() / 2]);
      std::fflush(stdout);
    }
  }
}
