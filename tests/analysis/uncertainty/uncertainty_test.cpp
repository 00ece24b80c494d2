// The expanded uncertainties against constructed truth (docs/uncertainty.md, issue 41): profiles
// with known springback, curl and radius (simulators/parts), at seeds and poses of this test's
// own, analysed end to end; per kind of value the share of |measured - true| <= U lies within
// [90 %, 99.5 %] (honest, not padded), and per kind and family the median U is at most 3x the
// observed 2 rms error (or 0.006 deg / mm, whichever is larger). The production solids and
// one-sided views are in bench/uncertainty_sweep (seconds each, too slow for the suite).
#include "analysis/uncertainty/uncertainty.hpp"

#include <gtest/gtest.h>

#include "analysis/uncertainty/fit_covariance.hpp"
#include "tests/analysis/uncertainty/coverage_study.hpp"
#include "tests/analysis/under_sanitizer.hpp"

namespace springscan::analysis {
namespace {

using testing::kUnderSanitizer;

// A plane of known noise: the slope variance is the textbook sigma^2 / sum (s - mean)^2.
TEST(FitCovariance, PlaneSlopeVarianceIsTheLineFitsFormula) {
  std::vector<Vec3> local;
  std::mt19937 rng(7);
  std::normal_distribution<double> noise(0.0, 0.05);
  double sum_s2 = 0.0;
  for (int i = 0; i < 40; ++i)
    for (int j = 0; j < 10; ++j) {
      const double s = i - 19.5, t = 3.0 * j;
      local.emplace_back(s, t, 0.01 * s + noise(rng));
      sum_s2 += s * s;
    }
  const PlaneCovariance plane = plane_covariance(local, {});
  ASSERT_TRUE(plane.ok);
  EXPECT_NEAR(plane.sigma_mm, 0.05, 0.005);
  EXPECT_NEAR(plane.slope_variance({1.0, 0.0}, 1.0), 1.0 / sum_s2, 1e-12);
  EXPECT_FALSE(plane_covariance(std::span<const Vec3>(local.data(), 4), {}).ok);  // tiny input
  EXPECT_FALSE(plane_covariance({}, {}).ok);                                      // empty
}

TEST(Uncertainty, SettingsOutOfRangeAreNamed) {
  UncertaintySettings st;
  st.scanner_sigma_mm = -1.0;
  const auto error = validate(st);
  ASSERT_TRUE(error);
  EXPECT_NE(error->message.find("uncertainty.scanner_sigma_mm"), std::string::npos);
  EXPECT_FALSE(validate(UncertaintySettings{}));
}

// The station's terms only add: a calibration angle of 0.01 deg is in every angle's U.
TEST(Uncertainty, StationTermsAddByRootSumOfSquares) {
  const auto model = parts::profile_part_model(parts::l_profile(40, 35, 90, 3), {20000});
  ASSERT_TRUE(model);
  parts::ScanSimulationSettings sim;
  sim.point_count = 20000;
  sim.with_normals = true;
  sim.seed = 515;
  const auto scan = parts::simulate_scan(parts::l_profile(40, 35, 90, 3), {1.0}, sim);
  ASSERT_TRUE(scan);
  v1::AnalysisSettings settings;
  const auto plain = run_inspection(*model, *scan, settings);
  settings.mutable_uncertainty()->set_calibration_angle_deg(0.01);
  const auto station = run_inspection(*model, *scan, settings);
  ASSERT_TRUE(plain && station);
  const double u0 = plain->report.bends(0).springback_uncertainty_deg() / 2.0;
  const double u1 = station->report.bends(0).springback_uncertainty_deg() / 2.0;
  EXPECT_GT(u0, 0.0);
  EXPECT_NEAR(u1 * u1, u0 * u0 + 0.01 * 0.01, 1e-9);
  EXPECT_DOUBLE_EQ(station->report.settings().uncertainty().calibration_angle_deg(), 0.01);
  settings.mutable_uncertainty()->set_temperature_delta_k(1000.0);
  EXPECT_FALSE(run_inspection(*model, *scan, settings));
}

TEST(Uncertainty, CoversTheTruthOfProfilesHonestly) {
  // Seeds of this test only (never accuracy_sweep's held-out ones).
  std::mt19937_64 rng(770077);
  const int per_family = kUnderSanitizer ? 1 : 6;
  testing::CoverageStudy study;
  using testing::ProfileFamily;
  for (ProfileFamily f : {ProfileFamily::kClean, ProfileFamily::kNoisy, ProfileFamily::kCurled,
                          ProfileFamily::kShortFlange})
    for (int k = 0; k < per_family; ++k) testing::run_profile_case(f, rng, 30000, study);
  // The profiles are built with no two orientations alike (coverage_study.hpp): no fit may be
  // ambiguous, and none is left out of the table.
  EXPECT_EQ(study.ambiguous, 0);
  const std::vector<testing::CoverageSample>& samples = study.samples;
  for (const testing::CoverageSample& s : samples) {
    EXPECT_TRUE(std::isfinite(s.U) && s.U > 0.0) << s.kind << " " << s.family;
  }
  if (kUnderSanitizer) return;  // too few values for a coverage
  const auto rows = testing::coverage_table(samples);
  testing::print_table(rows);
  // Per kind over the families: within [90 %, 99.5 %].
  std::map<std::string, std::pair<double, double>> per_kind;  // covered, values
  for (const testing::CoverageRow& r : rows) {
    per_kind[r.kind].first += r.covered * static_cast<double>(r.values);
    per_kind[r.kind].second += static_cast<double>(r.values);
  }
  for (const auto& [kind, count] : per_kind) {
    if (count.second < 20) continue;  // a kind few cases show (curl radius): the bench's
    EXPECT_GE(count.first / count.second, 0.90) << kind;
    EXPECT_LE(count.first / count.second, 0.995) << kind;
  }
  // Per kind and family: U not padded.
  for (const testing::CoverageRow& r : rows) {
    if (r.kind == "curl radius") continue;
    EXPECT_LE(r.median_U, std::max(3.0 * r.two_rms_error, 0.006)) << r.kind << ", " << r.family;
  }
}

}  // namespace
}  // namespace springscan::analysis
