// The deformation field and the compensation against the constructed truth: L, U, Z
// and hat profiles and the four openamr parts, produced with springback 0.2-3 deg, posed at
// random, laser-scanned in two tilted passes, analysed by run_inspection. The truth of each
// control point is the produced position of its CAD point in the CAD frame, placed by the
// construction alone (field_truth.hpp): an error of the report's result frame is measured.
//
// The contrast table of docs/matching.md comes from these cases:
//   ./build/tests/analysis/springscan_analysis_tests --gtest_filter='FieldAccuracy.*Contrast*'
#include <gtest/gtest.h>

#include <iostream>
#include <random>

#include "tests/analysis/matching/field_truth.hpp"
#include "tests/analysis/synthetic.hpp"

namespace springscan::analysis {
namespace {

using testing::field_errors;
using testing::FieldRun;
using testing::FieldScenario;

struct PartCase {
  std::string name;
  bool profile = false;
  parts::ProfileSpec spec;
  std::vector<double> springback_deg;
};

// Asymmetric lengths: a symmetric profile has two best fits, and the material point of a
// control point would be ambiguous.
std::vector<PartCase> part_cases() {
  using parts::ProfileSpec;
  std::vector<PartCase> out;
  out.push_back({"L", true, ProfileSpec{{70.0, 45.0}, {90.0}, {3.0}, 60.0, 0.0}, {1.7}});
  out.push_back({"U",
                 true,
                 ProfileSpec{{35.0, 80.0, 25.0}, {90.0, 90.0}, {4.0, 4.0}, 60.0, 0.0},
                 {2.5, 0.6}});
  out.push_back({"Z",
                 true,
                 ProfileSpec{{40.0, 60.0, 30.0}, {80.0, -80.0}, {3.0, 3.0}, 60.0, 0.0},
                 {0.3, 1.4}});
  out.push_back({"hat",
                 true,
                 ProfileSpec{{30.0, 40.0, 60.0, 35.0, 25.0},
                             {90.0, -90.0, -90.0, 90.0},
                             {4.0, 4.0, 4.0, 4.0},
                             60.0,
                             0.0},
                 {1.2, 2.0, 0.2, 3.0}});
  out.push_back({"openamr-MMP.03.00.00.003_Motor_bracket.step", false, {}, {1.5, 0.8, 2.2, 0.5}});
  out.push_back({"openamr-MMP.00.00.00.001_Front_panel.step", false, {}, {0.4, 0.25, 0.6, 0.3}});
  // Three closed hems (springback 0 whatever is asked) beside five bends.
  out.push_back(
      {"openamr-MMP.01.00.00.002_Cover_flange.step", false, {}, {0.5, 1.2, 0.3, 0.8, 1.6, 0.4}});
  // 16 bends, most of them short tabs the passes see little of (their bends unmeasured).
  out.push_back({"openamr-MMP.00.00.00.003_Side_panel.step",
                 false,
                 {},
                 {0.6, 0.3, 1.1, 0.5, 0.9, 0.2, 1.4, 0.7}});
  return out;
}

const parts::CadPart& cad_of(const PartCase& c) {
  return testing::field_part(c.name, c.profile ? &c.spec : nullptr);
}

Transform random_pose(unsigned seed) {
  std::mt19937 rng(seed);
  return testing::random_motion(rng, 200.0);
}

// Control point -> compensation vector, matched by position (the report lists supported ones).
double compensation_p95(const FieldRun& run, double alpha) {
  const KdTree control(run.control);
  std::vector<double> err;
  for (const auto& c : run.report.compensation()) {
    const auto i = control.nearest(testing::vec(c.point()), 1e-6);
    if (!i) continue;
    const Vec3 truth = -alpha * (run.truth[i->index] - run.control[i->index]);
    err.push_back((testing::vec(c.vector()) - truth).norm());
  }
  return testing::p95(err);
}

class FieldAccuracy : public ::testing::TestWithParam<int> {
 protected:
  void SetUp() override {
    if (testing::kUnderSanitizer &&
        part_cases()[static_cast<std::size_t>(GetParam())].profile == false)
      GTEST_SKIP() << "a production part: the release suite runs it";
  }
};

TEST_P(FieldAccuracy, SubSampleAgainstTheProducedTruth) {
  const PartCase c = part_cases()[static_cast<std::size_t>(GetParam())];
  const auto& cad = cad_of(c);
  FieldScenario sc;
  sc.springback_deg = c.springback_deg;
  sc.pose = random_pose(100u + static_cast<unsigned>(GetParam()));
  const FieldRun run = testing::run_field_case(cad, sc);
  const auto& field = run.report.deformation_field();
  ASSERT_GT(field.vectors_size(), 20) << c.name;
  EXPECT_EQ(field.refinement(), "flange_motion_surface");
  EXPECT_EQ(field.matching_size(), std::min(field.model_points(), field.scan_points()));
  const auto e = field_errors(run, field.vectors());
  std::printf("%s: p95 %.4f / %.4f mm, max %.4f mm, result frame off by up to %.4f mm\n",
              c.name.c_str(), e.p95_normal, e.p95_full, e.max_full, run.frame_error_mm);
  // docs/matching.md: 0.05 mm along the normal. The full vector also holds the frame's slide
  // along edge-on walls (front panel 0.059, cover flange 0.066 mm at p95): 0.1, and so its max.
  EXPECT_LE(e.p95_normal, 0.05) << c.name;
  EXPECT_LE(e.p95_full, 0.1) << c.name;
  EXPECT_LE(e.max_full, 0.1) << c.name;
  EXPECT_LE(run.frame_error_mm, 0.1) << c.name;
  EXPECT_LE(compensation_p95(run, 1.0), 0.1) << c.name;
  EXPECT_LT(field.residual_rms_mm(), 0.04) << c.name;
  // Coverage of the scanned area: every control point with scan all round it has a vector.
  std::vector<bool> has(run.control.size(), false);
  for (const auto& v : field.vectors()) has[static_cast<std::size_t>(v.model_index())] = true;
  for (std::size_t i = 0; i < run.control.size(); ++i) {
    if (run.scanned_points[i] >= 30) {
      EXPECT_TRUE(has[i]) << c.name << " control point " << i;
    }
  }
  for (const auto& v : field.vectors()) EXPECT_GT(v.uncertainty_mm(), 0.0);
  // The safety clip is not reached by a correct field.
  for (const auto& w : run.report.warnings()) EXPECT_EQ(w.find("clipped"), std::string::npos) << w;
  // Only the front panel's translation along y (its walls across y edge-on, too few strips of
  // the scan across the part end to end) is the alignment's, and the report says so.
  int from_fit = 0;
  for (const auto& w : run.report.warnings())
    if (w.find("deformation field: its translation along") != std::string::npos) {
      ++from_fit;
      EXPECT_NE(w.find("1.000"), std::string::npos) << w;  // along y, either sign
    }
  EXPECT_EQ(from_fit, c.name.find("Front_panel") != std::string::npos ? 1 : 0) << c.name;
}

TEST_P(FieldAccuracy, NoisyScanWithOutliersAndMissingAreas) {
  const PartCase c = part_cases()[static_cast<std::size_t>(GetParam())];
  FieldScenario sc;
  sc.springback_deg = c.springback_deg;
  sc.pose = random_pose(200u + static_cast<unsigned>(GetParam()));
  sc.noise_mm = 0.05;
  sc.outliers = 0.02;
  sc.missing = 0.10;
  const FieldRun run = testing::run_field_case(cad_of(c), sc);
  const auto& field = run.report.deformation_field();
  ASSERT_GT(field.vectors_size(), 20) << c.name;
  const auto noisy = field_errors(run, field.vectors());
  std::printf("%s noisy: p95 %.4f / %.4f mm, max %.4f mm, result frame off by up to %.4f mm\n",
              c.name.c_str(), noisy.p95_normal, noisy.p95_full, noisy.max_full, run.frame_error_mm);
  // Measured 0.026-0.116 mm at p95 and at most 0.122 mm (side panel): within 0.15 both.
  EXPECT_LE(noisy.p95_full, 0.15) << c.name;
  EXPECT_LE(noisy.max_full, 0.15) << c.name;
  // The missing areas are reported as not covered.
  std::vector<bool> has(run.control.size(), false);
  for (const auto& v : field.vectors()) has[static_cast<std::size_t>(v.model_index())] = true;
  int missing = 0;
  for (std::size_t i = 0; i < run.control.size(); ++i)
    if (run.scanned_points[i] == 0) {
      EXPECT_FALSE(has[i]) << c.name << " control point " << i;
      ++missing;
    }
  EXPECT_EQ(static_cast<std::size_t>(field.uncovered_model_indices_size()),
            run.control.size() - static_cast<std::size_t>(field.vectors_size()));
  std::printf("%s: p95 %.4f mm as a full vector, %d control points in missing areas\n",
              c.name.c_str(), field_errors(run, field.vectors()).p95_full, missing);
}

TEST_P(FieldAccuracy, ZeroSpringbackGivesZeroVectors) {
  const PartCase c = part_cases()[static_cast<std::size_t>(GetParam())];
  FieldScenario sc;
  sc.springback_deg = {0.0};
  sc.pose = random_pose(300u + static_cast<unsigned>(GetParam()));
  // A solid's passes tilt about a diagonal of its edges, so that every wall is seen: the side
  // panel's notched wall, which alone tells it from its half turn, too (docs/alignment.md
  // "Near-symmetry"; tilted about its length that wall is edge-on and the part is reported
  // ambiguous, production_parts_test.cpp).
  if (!c.profile) sc.tilt_axis_deg = 45.0;
  const FieldRun run = testing::run_field_case(cad_of(c), sc);
  std::printf("%s: orientation by %s (ratio %.3f)\n", c.name.c_str(),
              run.report.global_fit().orientation_decided_by().c_str(),
              run.report.global_fit().orientation_ambiguity());
  ASSERT_FALSE(run.report.global_fit().ambiguous()) << c.name;
  ASSERT_GT(run.report.deformation_field().vectors_size(), 20) << c.name;
  // Nothing sprang back: the truth is the CAD part itself in the CAD frame, every vector is
  // zero, and whatever a vector holds is error (the result frame's among it). Within the noise
  // bound of the sub-sample field, 0.05 mm, at p95 and at the worst vector.
  const auto e = field_errors(run, run.report.deformation_field().vectors());
  std::vector<double> length;
  for (const auto& v : run.report.deformation_field().vectors())
    length.push_back((testing::vec(v.scan()) - testing::vec(v.model())).norm());
  std::printf("%s zero springback: vectors p95 %.4f max %.4f mm; result frame off by %.4f mm\n",
              c.name.c_str(), testing::p95(length), e.max_length, run.frame_error_mm);
  EXPECT_LE(testing::p95(length), 0.05) << c.name;
  EXPECT_LE(e.max_length, 0.05) << c.name;
  EXPECT_LE(e.max_full, 0.05) << c.name;
  EXPECT_LE(run.frame_error_mm, 0.05) << c.name;
}

// As the station's laser driver delivers a scan: points only, the part facing the scanner (+z
// of the scan frame) within 30 deg. On a solid the refinement estimates the normals of the scan
// points near its predictions, turned toward the scanner's viewpoint, and step 4's cone judges
// them: the same bounds as with the scanner's normals. (Without them the motor bracket's 2 mm
// rims took their offsets from the skins beside them: p95 0.26 mm along the normal.)
class FieldAccuracyPointsOnly : public FieldAccuracy {};

// The bounds of a points-only case against the truth in the CAD frame (mm): p95 along the
// normal, p95 and max as a full vector; and the field's shape alone (p95 full vector in the
// report's own frame). A scan with normals meets 0.05 / 0.1 / 0.1 on every part (above), and so
// do the profiles and the motor bracket facing the scanner here. The other solids are looser,
// each measured at about half its bound (this file's commit, docs/matching.md "Truth in the
// CAD frame"): with points only a solid's frame rests on normals estimated from the points, and
// the result frame is off against the best fit of the seen surface by 0.08 mm (motor bracket
// about the diagonal), 0.26 / 0.44 mm (front panel: its translation along y is pinned by the
// edge strips, docs/matching.md step 2), 0.09 / 0.22 mm (cover flange, its hems) and 0.05 mm
// (side panel, whose field's shape is 0.15 mm off along the surface there): issue 32's "poses
// under noise". A frame error is in every vector, so it is bounded here, never cancelled.
struct PointsOnlyBound {
  double p95_normal = 0.05, p95_full = 0.1, max_full = 0.1, shape_p95_full = 0.1;
};

PointsOnlyBound points_only_bound(const std::string& name, bool diagonal) {
  const auto is = [&](const char* part) { return name.find(part) != std::string::npos; };
  if (is("Motor_bracket") && diagonal) return {0.08, 0.12, 0.12, 0.1};
  if (is("Front_panel"))
    return diagonal ? PointsOnlyBound{0.1, 0.7, 0.8, 0.1} : PointsOnlyBound{0.2, 0.4, 0.4, 0.1};
  if (is("Cover_flange"))
    return diagonal ? PointsOnlyBound{0.15, 0.3, 0.3, 0.1} : PointsOnlyBound{0.05, 0.1, 0.2, 0.1};
  if (is("Side_panel") && diagonal) return {0.06, 0.3, 0.3, 0.25};
  return {};
}

// One points-only case: the pose facing the scanner; `tilt_axis_deg` the passes' tilt axis
// (FieldScenario; negative: its default).
void check_points_only(const PartCase& c, double tilt_axis_deg) {
  FieldScenario sc;
  sc.springback_deg = c.springback_deg;
  sc.scanner_normals = false;
  sc.pose = Eigen::Translation3d(40.0, -25.0, 300.0) *
            Eigen::AngleAxisd(0.5, Vec3(0.2, 0.3, 1.0).normalized());
  if (tilt_axis_deg >= 0.0) sc.tilt_axis_deg = tilt_axis_deg;
  const FieldRun run = testing::run_field_case(cad_of(c), sc);
  const auto& field = run.report.deformation_field();
  ASSERT_GT(field.vectors_size(), 20) << c.name;
  ASSERT_FALSE(run.report.global_fit().ambiguous()) << c.name;
  const auto e = field_errors(run, field.vectors());
  const auto shape = field_errors(run, field.vectors(), true);
  std::printf(
      "%s points only (tilt axis %.0f deg): p95 %.4f / %.4f mm, max %.4f mm over %zu vectors; "
      "result frame off by up to %.4f mm; in the report's frame p95 %.4f / %.4f mm\n",
      c.name.c_str(), sc.tilt_axis_deg, e.p95_normal, e.p95_full, e.max_full, e.vectors,
      run.frame_error_mm, shape.p95_normal, shape.p95_full);
  const PointsOnlyBound bound = points_only_bound(c.name, tilt_axis_deg == 45.0);
  EXPECT_LE(e.p95_normal, bound.p95_normal) << c.name;
  EXPECT_LE(e.p95_full, bound.p95_full) << c.name;
  EXPECT_LE(e.max_full, bound.max_full) << c.name;
  EXPECT_LE(shape.p95_full, bound.shape_p95_full) << c.name;
  EXPECT_LT(field.residual_rms_mm(), 0.04) << c.name;
}

TEST_P(FieldAccuracyPointsOnly, SubSampleAgainstTheProducedTruth) {
  check_points_only(part_cases()[static_cast<std::size_t>(GetParam())], -1.0);
}

// The passes tilted about a diagonal of the part's edges, as the production parts' tests scan
// them, so that every wall is seen: the side panel's notched wall too, which alone tells it
// from its half turn (docs/alignment.md "Near-symmetry"; in the pose above it is edge-on and
// the part is reported ambiguous).
class FieldAccuracyPointsOnlyDiagonal : public FieldAccuracy {};

TEST_P(FieldAccuracyPointsOnlyDiagonal, SubSampleAgainstTheProducedTruth) {
  check_points_only(part_cases()[static_cast<std::size_t>(GetParam())], 45.0);
}

// Prints the contrast table of docs/matching.md: nearest neighbour, the raw matching and the
// refined field against the truth (p95 along the normal / full vector, mm).
TEST_P(FieldAccuracy, ContrastTable) {
  if (testing::kUnderSanitizer) GTEST_SKIP() << "a figures table: the release suite prints it";
  const PartCase c = part_cases()[static_cast<std::size_t>(GetParam())];
  FieldScenario sc;
  sc.springback_deg = c.springback_deg;
  sc.pose = random_pose(100u + static_cast<unsigned>(GetParam()));
  v1::AnalysisSettings nn;
  nn.mutable_deformation_field()->set_method(v1::DeformationFieldSettings::NEAREST_NEIGHBOR);
  const FieldRun a = testing::run_field_case(cad_of(c), sc, nn);
  const FieldRun b = testing::run_field_case(cad_of(c), sc);
  const auto e_nn = field_errors(a, a.report.deformation_field().matching());
  const auto e_raw = field_errors(b, b.report.deformation_field().matching());
  const auto e_ref = field_errors(b, b.report.deformation_field().vectors());
  double truth_median = 0.0;
  {
    std::vector<double> t;
    for (std::size_t i = 0; i < b.truth.size(); ++i)
      t.push_back((b.truth[i] - b.control[i]).norm());
    std::nth_element(t.begin(), t.begin() + static_cast<long>(t.size() / 2), t.end());
    truth_median = t[t.size() / 2];
  }
  std::printf("| %s | %.2f | %.3f / %.3f | %.3f / %.3f | %.4f / %.4f | %.0f %% |\n", c.name.c_str(),
              truth_median, e_nn.p95_normal, e_nn.p95_full, e_raw.p95_normal, e_raw.p95_full,
              e_ref.p95_normal, e_ref.p95_full,
              100.0 * b.report.deformation_field().scan_coverage());
  EXPECT_LT(e_ref.p95_full, e_raw.p95_full);
}

std::string case_name(const ::testing::TestParamInfo<int>& param) {
  const std::string n = part_cases()[static_cast<std::size_t>(param.param)].name;
  if (n.size() < 8) return n;
  for (const auto& [file, name] : {std::pair{"Motor", "MotorBracket"},
                                   {"Front", "FrontPanel"},
                                   {"Cover", "CoverFlange"},
                                   {"Side", "SidePanel"}})
    if (n.find(file) != std::string::npos) return name;
  return "Part" + std::to_string(param.param);
}

INSTANTIATE_TEST_SUITE_P(Parts, FieldAccuracy, ::testing::Range(0, 4), case_name);
// The openamr parts are solid sheets scanned from one side (docs/matching.md "Refined field",
// solids): the unseen skin has no vector, hole walls and sheet edges are supported by their own
// scan only. The front panel's two 18 mm walls facing along y are seen edge-on by these passes
// (tilted about y): their fits are rejected, their bends unmeasured, their rims get no vector,
// and the translation along y is the best fit's, pinned at the part's ends. The cover flange's
// closed hems and the side panel's unseen tabs are reached through unmeasured bends: no vector,
// and no say in the part's motion. Release only: 1-5 s a case there, minutes under the sanitizers.
INSTANTIATE_TEST_SUITE_P(SolidParts, FieldAccuracy, ::testing::Range(4, 8), case_name);
// Points only: the four profiles (surfaces: no normals needed; the U's half turn, which its
// mean error could not tell from this pose, is decided by its decisive points) and the motor
// bracket, the front panel and the cover flange (its hems' bias corrected by the exact-surface
// updates, the scan points lent their nearest fit point's normal). The front panel's walls
// facing along y are edge-on here: its translation along y is the best fit's, pinned at the
// part's ends (docs/matching.md step 2). The side panel's notched wall is not in this scan and
// its fit is reported ambiguous: scanned with the passes about the diagonal it is measured
// (below).
INSTANTIATE_TEST_SUITE_P(Parts, FieldAccuracyPointsOnly, ::testing::Range(0, 4), case_name);
INSTANTIATE_TEST_SUITE_P(SolidParts, FieldAccuracyPointsOnly, ::testing::Range(4, 7), case_name);
// All four openamr parts.
INSTANTIATE_TEST_SUITE_P(SolidParts, FieldAccuracyPointsOnlyDiagonal, ::testing::Range(4, 8),
                         case_name);

}  // namespace
}  // namespace springscan::analysis
