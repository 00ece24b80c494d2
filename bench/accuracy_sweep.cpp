// Accuracy on fresh draws: every number of a case comes from the seed, so a run at a seed
// nobody tuned to measures what the station does on parts it never saw (issue 39).
//
//   ./build/bench/accuracy_sweep --seed S [--cases N] [--points P] [--perfect]
//
// Each case draws a part (a random profile, L to five flanges, surface or 2 mm solid; or one of
// the production solids of ../shared/data/cad), a springback per bend (0-3 deg, some exactly 0),
// a pose (any, or with points only facing the scanner within 30 deg), a view (passes tilted about
// the part's length or a diagonal, from above or, with the scanner's normals, from below) and noise
// (sigma 0.02 or 0.05 mm, and then 2 % outliers and 10 % missing), produces, scans and analyses it
// (run_inspection, as the station), and prints: per bend the truth, the measured springback and the
// error, or why it has none; per case the result frame's error against the truth placed by the
// construction alone (field_truth.hpp) and the deformation field's p95 and max error; and a summary
// line. A case the station reports ambiguous (it cannot tell the part from its turned copy) is
// counted apart: its bends are not judged, but the part must fail. It fails (exit 1) only on a
// crash, a bend off by more than 1 deg, or an ambiguous part passed: CI runs it at a seed derived
// from the commit to report, without blocking, while accuracy is being fixed (docs/springback.md
// keeps each landing's summary). --perfect makes every part as drawn (no springback: the same
// draws otherwise): the true result frame is then the identity, so each case prints its pose
// error (rotation, largest shift over the part) and whether the verdict passed it, and the
// summary counts the perfect parts that failed and the poses beyond 0.05 deg / 0.05 mm.
#include <google/protobuf/text_format.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "tests/analysis/matching/field_truth.hpp"
#include "tests/analysis/synthetic.hpp"
#include "tests/simulators/parts/production_parts.hpp"

namespace springscan::analysis {
namespace {

struct SweepOptions {
  std::uint64_t seed = 1;
  int cases = 24;
  std::int64_t points = 200'000;
  int only = -1;                  ///< run this case alone (the draws before it are still made)
  bool perfect = false;           ///< every springback 0: the part as the CAD, posed
  v1::AnalysisSettings settings;  ///< the analysis settings (--settings FILE.textproto)
};

struct Summary {
  int cases = 0, ambiguous = 0, ambiguous_but_shown = 0, ambiguous_passed = 0, bends = 0,
      measured = 0, off_by_1deg = 0;
  int crashes = 0, skipped = 0;
  int perfect_failed = 0, perfect_undecided = 0;  ///< --perfect: verdicts FAIL / UNDECIDED
  int pose_beyond = 0;                            ///< --perfect: poses off by more than 0.05
  double worst_rotation_deg = 0.0;
  std::vector<double> bend_errors;
  double worst_frame_mm = 0.0, worst_field_p95_mm = 0.0;
};

using parts::testing::production_parts;  // the shared CAD folder's production parts

// A random open profile: 2-5 flanges of 20-80 mm, turns of 60-100 deg either way, radii 1.5-5
// mm, 40-120 mm wide; a surface or a 2 mm solid.
parts::ProfileSpec random_profile(std::mt19937_64& rng) {
  std::uniform_int_distribution<int> flanges(2, 5);
  std::uniform_real_distribution<double> length(20.0, 80.0), turn(60.0, 100.0), radius(1.5, 5.0),
      width(40.0, 120.0), unit(0.0, 1.0);
  parts::ProfileSpec spec;
  const int n = flanges(rng);
  for (int k = 0; k < n; ++k) spec.flange_lengths_mm.push_back(length(rng));
  for (int k = 0; k + 1 < n; ++k) {
    spec.bend_angles_deg.push_back((unit(rng) < 0.5 ? -1.0 : 1.0) * turn(rng));
    spec.bend_radii_mm.push_back(radius(rng));
  }
  spec.width_mm = width(rng);
  spec.thickness_mm = unit(rng) < 0.5 ? 0.0 : 2.0;
  return spec;
}

std::string describe(const parts::ProfileSpec& spec) {
  std::string out = spec.thickness_mm > 0 ? "solid profile" : "profile";
  char buf[64];
  // The first flange's length, then each turn and the flange after it (the first was printed
  // as 0 before issue 32's round of 2026-12-07).
  for (std::size_t k = 0; k < spec.flange_lengths_mm.size(); ++k) {
    if (k == 0)
      std::snprintf(buf, sizeof buf, " %.0f", spec.flange_lengths_mm[0]);
    else
      std::snprintf(buf, sizeof buf, " %+.0f/%.0f", spec.bend_angles_deg[k - 1],
                    spec.flange_lengths_mm[k]);
    out += buf;
  }
  return out;
}

// --perfect: nothing sprang back, so the true result frame is the identity and every
// characteristic conforms; the verdict must be PASS (issue 32: "perfect parts pass") and the pose
// within 0.05 deg / 0.05 mm. A verdict other than PASS prints its reasons.
void judge_perfect_part(const testing::FieldRun& run, Summary& sum) {
  const double rotation_deg =
      Eigen::AngleAxisd(run.T_result_part.linear()).angle() * 180.0 / std::numbers::pi;
  sum.worst_rotation_deg = std::max(sum.worst_rotation_deg, rotation_deg);
  const bool beyond = rotation_deg > 0.05 || run.frame_error_mm > 0.05;
  sum.pose_beyond += beyond ? 1 : 0;
  const auto& verdict = run.report.verdict();
  std::printf("  perfect part: pose %.4f deg, %.4f mm%s; verdict %s\n", rotation_deg,
              run.frame_error_mm, beyond ? " (beyond 0.05)" : "",
              v1::Verdict::Decision_Name(verdict.decision()).c_str());
  if (verdict.decision() == v1::Verdict::PASS) return;
  if (verdict.decision() == v1::Verdict::FAIL) ++sum.perfect_failed;
  if (verdict.decision() == v1::Verdict::UNDECIDED) ++sum.perfect_undecided;
  for (const std::string& reason : verdict.reasons()) std::printf("    %s\n", reason.c_str());
}

// One case: draw, produce, scan, analyse, print; adds to `sum`.
void run_case(int index, std::mt19937_64& rng, const SweepOptions& options, Summary& sum) {
  std::uniform_real_distribution<double> unit(0.0, 1.0), springback(0.0, 3.0);
  const bool production = index % 2 == 1;
  std::string name;
  parts::ProfileSpec spec;
  if (production) {
    name = production_parts()[rng() % production_parts().size()];
  } else {
    name = "sweep_" + std::to_string(options.seed) + "_" + std::to_string(index);
    // A draw whose path runs into itself is no part: drawn again (the generator's check).
    const std::string probe =
        (std::filesystem::temp_directory_path() / "springscan_sweep_probe.brep").string();
    do spec = random_profile(rng);
    while (!parts::write_profile_cad(spec, probe));
  }
  const parts::CadPart& cad = testing::field_part(name, production ? nullptr : &spec);
  testing::FieldScenario sc;
  for (std::size_t b = 0; b < cad.model.segmentation.bends.size(); ++b)
    sc.springback_deg.push_back(unit(rng) < 0.15 ? 0.0 : springback(rng));
  if (sc.springback_deg.empty()) sc.springback_deg.push_back(0.0);
  if (options.perfect) std::fill(sc.springback_deg.begin(), sc.springback_deg.end(), 0.0);
  std::mt19937 pose_rng(static_cast<std::uint32_t>(rng()));
  sc.pose = testing::random_motion(pose_rng, 500.0);
  sc.tilt_axis_deg = production || unit(rng) < 0.5 ? 45.0 : 0.0;
  sc.scanner_normals = unit(rng) < 0.7;
  if (!sc.scanner_normals) {
    // Points only, the station's normals are estimated toward a viewpoint above the scanner:
    // the part faces it within 30 deg (docs/alignment.md), any turn about the view.
    const double turn = 2.0 * std::numbers::pi * unit(rng),
                 azimuth = 2.0 * std::numbers::pi * unit(rng);
    const double tilt = std::numbers::pi / 6.0 * unit(rng);
    sc.pose = Eigen::Translation3d(sc.pose.translation()) *
              Eigen::AngleAxisd(tilt, Vec3(std::cos(azimuth), std::sin(azimuth), 0.0)) *
              Eigen::AngleAxisd(turn, Vec3::UnitZ());
  }
  // A points-only scan's normals are estimated toward the configured viewpoint (above the
  // scanner frame's +z): from below, only with the scanner's own normals.
  sc.from_below = sc.scanner_normals && unit(rng) < 0.3;
  const bool noisy = unit(rng) < 0.4;
  sc.noise_mm = noisy ? 0.05 : 0.02;
  sc.outliers = noisy ? 0.02 : 0.0;
  sc.missing = noisy ? 0.10 : 0.0;
  sc.points = options.points;
  sc.seed = rng() % 100000;
  if (options.only >= 0 && index != options.only) return;
  if (options.only >= 0) {  // the draw in full, to be rebuilt as a test case
    std::printf("draw: seed %llu, springback", static_cast<unsigned long long>(sc.seed));
    for (double d : sc.springback_deg) std::printf(" %.17g", d);
    std::printf(", pose");
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 4; ++c) std::printf(" %.17g", sc.pose.matrix()(r, c));
    std::printf("\n");
  }
  const testing::FieldRun run = testing::run_field_case(cad, sc, options.settings);
  if (run.bends.empty() && run.report.bends_size() == 0) {
    // The simulator could not produce this draw (run_field_case printed why): no part to judge.
    std::printf("case %d: %s | not produced by the simulator, skipped\n", index,
                production ? name.c_str() : describe(spec).c_str());
    ++sum.skipped;
    return;
  }
  const auto& report = run.report;
  const bool ambiguous = report.global_fit().ambiguous();
  const auto field = testing::field_errors(run, report.deformation_field().vectors());
  std::printf(
      "case %d: %s | sigma %.2f%s, passes about %.0f deg%s, %s | frame %.4f mm | field p95 %.4f "
      "max %.4f mm (%zu vectors)%s\n",
      index, production ? name.c_str() : describe(spec).c_str(), sc.noise_mm,
      noisy ? " +2% outliers -10%" : "", sc.tilt_axis_deg, sc.from_below ? " from below" : "",
      sc.scanner_normals ? "normals" : "points only", run.frame_error_mm, field.p95_full,
      field.max_full, field.vectors, ambiguous ? " | AMBIGUOUS" : "");
  ++sum.cases;
  if (options.only >= 0)  // one case looked at closely: what the station said about it
    for (const std::string& warning : report.warnings()) std::printf("  %s\n", warning.c_str());
  if (ambiguous) {
    // The station says it cannot tell the part from its turned copy: its bend table may be the
    // mirror image's, and the part must fail. Counted apart; a pass would be a wrong answer.
    ++sum.ambiguous;
    // Whether the view could have told: scan points that lie off the part's settled half turn,
    // from the construction (field_truth.hpp). A view that shows dozens of them is one the
    // station should have decided (issue 32); none, and ambiguous is the right answer.
    const int telling = testing::points_telling_the_half_turn(run, cad);
    std::printf(
        "  %d scan points tell it from its half turn about its least spread (construction)\n",
        telling);
    if (telling >= 20) ++sum.ambiguous_but_shown;
    for (const std::string& warning : report.warnings())
      if (options.only < 0 && warning.starts_with("global fit:"))
        std::printf("  %s\n", warning.c_str());
    if (report.verdict().pass()) {
      ++sum.ambiguous_passed;
      std::printf("  an ambiguous fit PASSED the part\n");
    }
    return;
  }
  sum.worst_frame_mm = std::max(sum.worst_frame_mm, run.frame_error_mm);
  if (options.perfect) judge_perfect_part(run, sum);
  sum.worst_field_p95_mm = std::max(sum.worst_field_p95_mm, field.p95_full);
  for (const parts::BendTruth& truth : run.bends) {
    const auto it = std::find_if(report.bends().begin(), report.bends().end(),
                                 [&](const v1::Bend& b) { return b.id() == truth.bend_id; });
    if (truth.hem) continue;
    ++sum.bends;
    if (it == report.bends().end() || !it->measured()) {
      std::printf("  bend %d (%.1f deg): truth %.3f, not measured: %s\n", truth.bend_id,
                  truth.nominal_angle_deg, truth.springback_deg,
                  it == report.bends().end() ? "not in the report" : it->status().c_str());
      continue;
    }
    const double error = it->springback_deg() - truth.springback_deg;
    ++sum.measured;
    sum.off_by_1deg += std::abs(error) > 1.0 ? 1 : 0;
    sum.bend_errors.push_back(std::abs(error));
    std::printf("  bend %d (%.1f deg): truth %.3f, measured %.3f, error %+.4f deg\n", truth.bend_id,
                truth.nominal_angle_deg, truth.springback_deg, it->springback_deg(), error);
  }
}

double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::nth_element(v.begin(), v.begin() + static_cast<long>(v.size() / 2), v.end());
  return v[v.size() / 2];
}

int run(const SweepOptions& options) {
  std::printf("accuracy_sweep --seed %llu --cases %d --points %lld\n",
              static_cast<unsigned long long>(options.seed), options.cases,
              static_cast<long long>(options.points));
  std::mt19937_64 rng(options.seed);
  Summary sum;
  for (int k = 0; k < options.cases; ++k) {
    try {
      run_case(k, rng, options, sum);
    } catch (const std::exception& e) {
      ++sum.crashes;
      std::printf("case %d: CRASH: %s\n", k, e.what());
    }
  }
  const double worst = sum.bend_errors.empty()
                           ? 0.0
                           : *std::max_element(sum.bend_errors.begin(), sum.bend_errors.end());
  std::printf(
      "summary: seed %llu, %d cases (%d not produced, %d reported ambiguous and failed, %d of "
      "them in a view that shows the half turn's difference, %d crashed); in the others %d of %d "
      "bends measured, springback error median %.4f / worst "
      "%.4f deg, %d off by > 1 deg; result frame worst %.4f mm; field p95 worst %.4f mm\n",
      static_cast<unsigned long long>(options.seed), sum.cases + sum.skipped, sum.skipped,
      sum.ambiguous, sum.ambiguous_but_shown, sum.crashes, sum.measured, sum.bends,
      median(sum.bend_errors), worst, sum.off_by_1deg, sum.worst_frame_mm, sum.worst_field_p95_mm);
  if (options.perfect)
    std::printf(
        "perfect parts: %d of %d FAILED (a false decision), %d UNDECIDED; pose worst %.4f deg / "
        "%.4f mm, %d beyond 0.05 deg or 0.05 mm\n",
        sum.perfect_failed, sum.cases - sum.ambiguous, sum.perfect_undecided,
        sum.worst_rotation_deg, sum.worst_frame_mm, sum.pose_beyond);
  return sum.crashes == 0 && sum.off_by_1deg == 0 && sum.ambiguous_passed == 0 ? 0 : 1;
}

}  // namespace
}  // namespace springscan::analysis

int main(int argc, char** argv) {
  springscan::analysis::SweepOptions options;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    const bool has_value = i + 1 < argc;
    if (arg == "--seed" && has_value) {
      options.seed = std::strtoull(argv[++i], nullptr, 0);
    } else if (arg == "--cases" && has_value) {
      options.cases = std::atoi(argv[++i]);
    } else if (arg == "--points" && has_value) {
      options.points = std::atoll(argv[++i]);
    } else if (arg == "--perfect") {
      options.perfect = true;
    } else if (arg == "--case" && has_value) {
      options.only = std::atoi(argv[++i]);
    } else if (arg == "--settings" && has_value) {
      std::ifstream in(argv[++i]);
      const std::string text((std::istreambuf_iterator<char>(in)),
                             std::istreambuf_iterator<char>());
      if (!in || !google::protobuf::TextFormat::ParseFromString(text, &options.settings)) {
        std::fprintf(stderr, "accuracy_sweep: cannot read %s as AnalysisSettings\n", argv[i]);
        return 2;
      }
    } else {
      std::fprintf(stderr,
                   "usage: accuracy_sweep [--seed S] [--cases N] [--points P] [--case K] "
                   "[--settings FILE] [--perfect]\n");
      return 2;
    }
  }
  if (options.cases < 1 || options.points < 1000) {
    std::fprintf(stderr, "accuracy_sweep: --cases >= 1 and --points >= 1000\n");
    return 2;
  }
  return springscan::analysis::run(options);
}
