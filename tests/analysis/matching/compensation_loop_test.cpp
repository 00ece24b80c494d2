// The compensation loop closed in simulation (docs/matching.md "Compensated CAD"): a part
// produced from the nominal CAD with a known springback per bend (simulators/parts), scanned,
// analysed (run_inspection), its die compensated (compensated_shape, the field by
// evaluate_field, F = 1) and written as STEP; the compensated die read back and produced with
// the SAME springback model (each bend of the die opened by the same angle), measured again.
// The form error is the truth: the noise-free produced surface where the scanner saw it, in the
// frame the analysis aligned the scan to, against the nominal CAD (p95 of |distance|).
#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <map>

#include "analysis/cad/compensated_solid.hpp"
#include "analysis/matching/field_evaluation.hpp"
#include "analysis/messages/matching_proto.hpp"
#include "tests/analysis/matching/field_truth.hpp"

namespace springscan::analysis {
namespace {

using testing::exact_model;
using testing::field_part;
using testing::from_row_major;
using testing::p95;
using testing::TempDir;

struct Measured {
  v1::InspectionReport report;
  double form_error_p95 = 0.0;  ///< truth, mm
  double form_error_max = 0.0;
  double measured_p95 = 0.0;  ///< p95 of |the report's signed deviation| (with the noise)
};

// Produces `die` with `springback`, scans it from above in two tilted passes, analyses it
// against the nominal part and measures the true form error.
Measured produce_and_measure(const parts::CadPart& nominal, const parts::CadPart& die,
                             const std::vector<double>& springback, std::int64_t points) {
  Measured m;
  auto part = parts::make_produced_part(die.model, die.shape, springback);
  EXPECT_TRUE(part) << part.message();
  if (!part) return m;
  parts::LaserScanSettings ls;
  ls.point_count = points / 2;
  ls.noise_sigma_mm = 0.01;
  ls.line_direction = Vec3(0.35, 1.0, 0.0).normalized();
  ls.threads = 2;
  PointCloud cloud;
  std::vector<Vec3> cad_points;
  std::vector<int> faces;
  for (const int side : {1, -1}) {
    const double tilt = 35.0 * std::numbers::pi / 180.0, axis = std::numbers::pi / 4.0;
    ls.view_direction = Vec3(side * std::sin(tilt) * std::cos(axis),
                             side * std::sin(tilt) * std::sin(axis), -std::cos(tilt));
    ls.seed = static_cast<std::uint64_t>(side + 2);
    auto pass = parts::laser_scan(*part, ls);
    EXPECT_TRUE(pass) << pass.message();
    if (!pass) return m;
    cloud.points.insert(cloud.points.end(), pass->cloud.points.begin(), pass->cloud.points.end());
    cloud.normals.insert(cloud.normals.end(), pass->cloud.normals.begin(),
                         pass->cloud.normals.end());
    cad_points.insert(cad_points.end(), pass->cad_points.begin(), pass->cad_points.end());
    faces.insert(faces.end(), pass->cloud.face_ids.begin(), pass->cloud.face_ids.end());
  }
  auto outcome = run_inspection(exact_model(nominal), cloud, {});
  EXPECT_TRUE(outcome) << outcome.message();
  if (!outcome) return m;
  m.report = outcome->report;
  const Transform T_result_scan = from_row_major(m.report.alignment().transform());
  const SurfaceDistance& distance = *exact_model(nominal).distance;
  std::vector<double> truth, measured;
  for (std::size_t j = 0; j < cad_points.size(); ++j) {
    const Vec3 q = T_result_scan * part->produced(cad_points[j], faces[j]);
    truth.push_back(std::abs(distance.closest(q).signed_distance_mm));
    m.form_error_max = std::max(m.form_error_max, truth.back());
  }
  for (const double d : outcome->deviation_cloud.scalars) measured.push_back(std::abs(d));
  m.form_error_p95 = p95(truth);
  m.measured_p95 = p95(measured);
  return m;
}

// The die moved by -F x the report's field, written as STEP and read back as a part.
parts::CadPart compensate(const parts::CadPart& die, const v1::InspectionReport& report,
                          const std::string& path) {
  auto field = from_proto(report.deformation_field());
  EXPECT_TRUE(field) << field.message();
  const OffsetField offsets = [&](const std::vector<Vec3>& points) {
    FieldEvaluationSettings fs;
    for (const auto& free : report.global_fit().free_directions())
      fs.free_directions.push_back(
          Vec3(free.direction().x(), free.direction().y(), free.direction().z()).normalized());
    auto at = evaluate_field(*field, points, fs);
    PointOffsets out;
    for (const Vec3& d : at.deformation) out.offset.push_back(-d);
    out.covered = at.covered;
    out.uncertainty_mm = at.spread_mm;
    return out;
  };
  auto moved = compensated_shape(die.shape, offsets);
  EXPECT_TRUE(moved) << moved.message();
  if (!moved) return {};
  for (const auto& f : moved->faces)
    if (f.surface == "bspline" && f.canonical_deviation_mm >= 0.0)
      std::printf("[ compensate ] face %d: B-spline, %.4f mm from a plane/cylinder\n", f.id,
                  f.canonical_deviation_mm);
  std::printf(
      "[ compensate ] refit deviation max %.4f mm, p95 %.4f mm, largest move %.3f mm, field "
      "uncertainty up to %.4f mm, largest edge tolerance %.4f mm\n",
      moved->max_deviation_mm, moved->p95_deviation_mm, moved->max_offset_mm,
      moved->max_uncertainty_mm, moved->max_tolerance_mm);
  EXPECT_TRUE(write_step_atomically(moved->shape, path));
  auto loaded = parts::load_cad_part(path);
  EXPECT_TRUE(loaded) << loaded.message();
  return loaded ? std::move(*loaded) : parts::CadPart{};
}

// Under the sanitizers the sparse case runs one round at its own density: at 20 000 points the
// hat profile's die still loses 2 of its 5 flanges (docs/matching.md), so it cannot shrink more.
constexpr std::int64_t kSanitizerPoints = 40'000;

struct LoopCase {
  std::string name;
  const parts::ProfileSpec* spec;  // null: a part of the shared CAD folder
  std::vector<double> springback_deg;
  std::int64_t points = 120'000;  ///< scan points per measurement
  double max_error_mm = 0.0;      ///< bound on the max form error after each round (0: none)
  /// Under the sanitizers: one round at kSanitizerPoints; false: the
  /// case is left to the Release build (its bounds need its density).
  bool under_sanitizer = false;
};

void PrintTo(const LoopCase& c, std::ostream* os) { *os << c.name; }

class CompensationLoop : public ::testing::TestWithParam<LoopCase> {};

TEST_P(CompensationLoop, ClosesWithinTwentyPercentThenFiftyMicrons) {
  const LoopCase& c = GetParam();
  // Under the sanitizers a round at 120 000 points takes a minute: the sparse case runs one
  // round there (the same code; the bound after one round is the 20 %).
  if (testing::kUnderSanitizer && !c.under_sanitizer) GTEST_SKIP() << "release builds only";
  const TempDir dir;
  const parts::CadPart& nominal = field_part(c.name, c.spec);
  ASSERT_FALSE(nominal.model.segmentation.bends.empty());
  std::vector<double> springback(nominal.model.segmentation.bends.size(), c.springback_deg.back());
  for (std::size_t b = 0; b < springback.size() && b < c.springback_deg.size(); ++b)
    springback[b] = c.springback_deg[b];
  const std::int64_t points = testing::kUnderSanitizer ? kSanitizerPoints : c.points;
  const int rounds = testing::kUnderSanitizer ? 1 : 3;
  parts::CadPart die = nominal;
  std::vector<double> errors;
  for (int round = 0; round <= rounds; ++round) {
    const Measured m = produce_and_measure(nominal, die, springback, points);
    ASSERT_TRUE(m.report.has_deformation_field());
    errors.push_back(m.form_error_p95);
    if (round > 0 && c.max_error_mm > 0.0) {
      EXPECT_LE(m.form_error_max, c.max_error_mm);
    }
    std::printf(
        "[ loop ] %s round %d: form error p95 %.4f mm (max %.4f), measured |dev| p95 "
        "%.4f mm\n",
        c.name.c_str(), round, m.form_error_p95, m.form_error_max, m.measured_p95);
    if (round == rounds) break;
    die = compensate(die, m.report, dir.file("die" + std::to_string(round + 1) + ".step"));
    ASSERT_EQ(die.model.face_count, nominal.model.face_count);
    ASSERT_EQ(die.model.segmentation.flanges.size(), nominal.model.segmentation.flanges.size());
    ASSERT_EQ(die.model.segmentation.bends.size(), nominal.model.segmentation.bends.size());
  }
  EXPECT_LE(errors[1], 0.2 * errors[0]);
  if (rounds == 3) {
    EXPECT_LE(errors[3], 0.05);
  }
}

const parts::ProfileSpec& hat_solid() {
  static const parts::ProfileSpec spec = [] {
    parts::ProfileSpec s = parts::hat_profile(30, 40, 50, 80, 3);
    s.thickness_mm = 1.5;
    s.width_mm = 60.0;
    return s;
  }();
  return spec;
}

std::string case_name(std::size_t index) {
  const char* names[] = {"HatProfile", "MotorBracket", "HatProfileSparseScan"};
  return names[index];
}

INSTANTIATE_TEST_SUITE_P(
    Parts, CompensationLoop,
    ::testing::Values(LoopCase{"hat_solid_loop", &hat_solid(), {2.0, 1.2, 1.6, 0.8}, 120'000, 0.1},
                      LoopCase{"openamr-MMP.03.00.00.003_Motor_bracket.step",
                               nullptr,
                               {1.5, 1.0, 2.0, 0.8},
                               120'000,
                               0.15},
                      // A third of the points: the field twice as noisy; its flanges must stay
                      // planes (docs/matching.md "Why planes and cylinders stay canonical").
                      LoopCase{
                          "hat_solid_loop", &hat_solid(), {2.0, 1.2, 1.6, 0.8}, 40'000, 0.1, true}),
    [](const ::testing::TestParamInfo<LoopCase>& param) { return case_name(param.index); });

}  // namespace
}  // namespace springscan::analysis
