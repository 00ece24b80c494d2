// The production parts of ../shared/data/cad end to end: each part produced with a random
// springback on every bend, posed at random (any rotation, up to 500 mm), laser-scanned from
// one side in two passes tilted +-35 deg (200k points, sigma 0.02 mm; tilted about a diagonal
// of the part's edges, so that every wall is seen, but in one case), analysed by
// run_inspection with the exact CAD distance, as the station loads a part. Checked against the
// constructed truth: the result frame of the global fit, and every bend's springback.
#include "tests/simulators/parts/production_parts.hpp"

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <array>
#include <cmath>
#include <cstdio>
#include <map>
#include <numbers>
#include <ostream>
#include <random>
#include <set>

#include "analysis/cad/distance.hpp"
#include "tests/analysis/matching/field_truth.hpp"
#include "tests/analysis/synthetic.hpp"

namespace springscan::analysis {
namespace {

using testing::FieldRun;
using testing::FieldScenario;

struct PartExpectation {
  std::string name;
  // Bends the two passes from above measure at least: both flanges seen. The others join a
  // wall they do not see or are closed hems; they must say why they have no angle.
  int measurable_bends = 0;
  // The largest error of the result frame with no springback: rotation (deg), and shift of
  // the part's centroid (mm).
  double max_rotation_deg = 0.05;
  double max_shift_mm = 0.05;
  double max_residual_mm = 0.1;   ///< the fit's residual to the surface, sigma 0.02 mm
  int measurable_from_below = 0;  ///< bends the two passes from below measure at least
  int measurable_noisy = 0;       ///< ... and the noisy scan
  /// Its turned copy differs only where some scans do not look: reported ambiguous (the part
  /// fails) when the scan does not show the difference, rather than found by chance. The side
  /// panel differs from its half turn about the sheet normal only by notches in one long wall:
  /// passes tilted about the diagonal see them (decided by the decisive points), the ones of
  /// ZeroSpringbackFitsThePose (tilted about the length, that wall edge-on) do not.
  bool near_symmetric = false;
  /// Points only, no springback (PointsOnlyScanFitsThePose): rotation (deg) and residual (mm).
  double points_only_rotation_deg = 0.05;
  double points_only_residual_mm = 0.1;
};

void PrintTo(const PartExpectation& part, std::ostream* os) { *os << part.name; }

const std::vector<PartExpectation>& expectations() {
  static const std::vector<PartExpectation> parts = {
      {"openamr-MMP.03.00.00.003_Motor_bracket.step", 4, 0.05, 0.05, 0.1, 4, 4},
      // Its closed hems' folds biased the sample-paired fit 0.16 deg and 0.16 mm; the final
      // updates on the exact surface take it to 0.0003 deg and 0.002 mm (docs/alignment.md),
      // and points only, with the fit points' normals lent to the scan's, 0.0013 deg (0.19
      // without them).
      {"openamr-MMP.01.00.00.002_Cover_flange.step", 5, 0.05, 0.05, 0.1, 5, 5},
      // Two of its 16 bends join walls the passes from above do not see (0 points): they say so.
      // From below all 16 are measured.
      {"openamr-MMP.00.00.00.003_Side_panel.step", 14, 0.05, 0.05, 0.1, 16, 13, true},
      {"openamr-MMP.00.00.00.001_Front_panel.step", 4, 0.05, 0.05, 0.1, 4, 4},
      {"nema-17-bracket.step", 1, 0.05, 0.05, 0.1, 1, 1}};
  // Under the sanitizers (5-15x slower) one part: they look for memory errors and races.
  static const std::vector<PartExpectation> one(parts.begin(), parts.begin() + 1);
  return testing::kUnderSanitizer ? one : parts;
}

class ProductionPart : public ::testing::TestWithParam<PartExpectation> {};

// Whether the test built a view that hides a near-symmetric part's asymmetry (no scan point
// tells), so that the part must be reported ambiguous; every other part and view must be found.
// A view that shows the asymmetry by a handful of points only is neither: the station needs 4
// telling points with company (docs/alignment.md), and no test builds such a view by chance.
bool view_hides_the_asymmetry(const PartExpectation& part, const FieldRun& run,
                              const parts::CadPart& cad) {
  if (!part.near_symmetric) return false;
  const int telling = testing::points_telling_the_half_turn(run, cad);
  std::printf("%s: %d scan points tell it from its half turn\n", part.name.c_str(), telling);
  EXPECT_TRUE(telling == 0 || telling >= 20)
      << telling << " telling points: the test's view must hide or show the asymmetry";
  return telling == 0;
}

// The passes tilt about a diagonal of the part's edges: each of them sees the walls facing
// two ways, so every wall of a box-like part is seen by one (tilted about an edge, the walls
// along the tilt axis are edge-on: 12 of the side panel's 16 bends had no angle).
constexpr double kTiltAxisDeg = 45.0;

// With no springback the produced part is the CAD part: the result frame is the identity.
// Checks it against the part's bounds; where the view hides a near-symmetric part's asymmetry
// (view_hides_the_asymmetry, from the construction) the part must be reported ambiguous and
// fail instead, and nowhere else.
void check_zero_springback_pose(const PartExpectation& part, double tilt_axis_deg) {
  const auto& cad = parts::testing::loaded_part(part.name);
  std::mt19937 rng(7);
  FieldScenario sc;
  sc.springback_deg = {0.0};
  sc.pose = testing::random_motion(rng, 500.0);
  sc.tilt_axis_deg = tilt_axis_deg;
  const FieldRun run = testing::run_field_case(cad, sc);
  const Transform& T = run.T_result_part;
  Vec3 centroid = Vec3::Zero();
  for (const Vec3& p : cad.model.samples.points) centroid += p;
  centroid /= static_cast<double>(cad.model.samples.size());
  const double rotation_deg = Eigen::AngleAxisd(T.linear()).angle() * 180.0 / std::numbers::pi;
  const double shift_mm = (T * centroid - centroid).norm();
  std::printf(
      "%s (passes tilted about %.0f deg): rotation %.4f deg, shift at the centroid %.4f mm, "
      "residual %.4f mm, orientation by %s (ratio %.3f)%s\n",
      part.name.c_str(), tilt_axis_deg, rotation_deg, shift_mm,
      run.report.global_fit().rms_residual(),
      run.report.global_fit().orientation_decided_by().c_str(),
      run.report.global_fit().orientation_ambiguity(),
      run.report.global_fit().ambiguous() ? ", ambiguous" : "");
  if (view_hides_the_asymmetry(part, run, cad)) {
    EXPECT_TRUE(run.report.global_fit().ambiguous()) << "turned silently or by chance";
    EXPECT_FALSE(run.report.verdict().pass()) << "an ambiguous fit never passes";
    return;
  }
  EXPECT_LE(rotation_deg, part.max_rotation_deg);
  EXPECT_LE(shift_mm, part.max_shift_mm);
  EXPECT_FALSE(run.report.global_fit().ambiguous());
  EXPECT_LE(run.report.global_fit().rms_residual(), part.max_residual_mm);
}

// The passes tilted about a diagonal of the part's edges (kTiltAxisDeg), as the springback
// cases below: every wall is seen, the side panel's notched one too, and every part is found.
TEST_P(ProductionPart, ZeroSpringbackFitsThePose) {
  check_zero_springback_pose(GetParam(), kTiltAxisDeg);
}

// The passes tilted about the part's length: the walls along it are edge-on. The side panel's
// notched wall is one of them, and no scan point tells it from its half turn (0 telling points):
// reported ambiguous, the part fails. The other parts are found.
TEST_P(ProductionPart, ZeroSpringbackPassesAboutTheLength) {
  check_zero_springback_pose(GetParam(), 0.0);
}

// Random springback 0.2-3 deg on every bend, as the issue asks.
FieldScenario random_springback(const parts::CadPart& cad, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> springback(0.2, 3.0);
  FieldScenario sc;
  for (std::size_t i = 0; i < cad.model.segmentation.bends.size(); ++i)
    sc.springback_deg.push_back(springback(rng));
  sc.pose = testing::random_motion(rng, 500.0);
  sc.tilt_axis_deg = kTiltAxisDeg;
  return sc;
}

// The bends this scan cannot measure by its construction: closed hems, and bends with a flange
// the scan does not see (fewer true scan points on its faces than the 50 a plane fit needs,
// counted from the simulator's face of every point, not from the report).
std::set<int> unmeasurable_by_construction(const FieldRun& run, const parts::CadPart& cad) {
  constexpr int kPlaneFitPoints = 50;
  std::map<int, int> seen_on_face;
  for (int face : run.scan_faces)
    if (face >= 0) ++seen_on_face[face];
  std::map<int, int> seen_on_flange;
  for (const Flange& f : cad.model.segmentation.flanges)
    for (int face : f.face_ids) seen_on_flange[f.id] += seen_on_face[face];
  std::set<int> out;
  for (const parts::BendTruth& b : run.bends)
    if (b.hem || seen_on_flange[b.parent_flange] < kPlaneFitPoints ||
        seen_on_flange[b.child_flange] < kPlaneFitPoints)
      out.insert(b.bend_id);
  return out;
}

struct BendCheck {
  int measured = 0;
  double worst = 0.0;                ///< largest |springback error| of a measured bend, deg
  std::map<int, double> springback;  ///< measured springback by bend id
};

// Every bend of the report against the produced part's truth: a closed hem listed as not
// measurable and passing, a bend without an angle saying why, exactly the bends the scan could
// not measure by construction (`unmeasurable`) without an angle, every other one measured within
// `bound` of its constructed springback and never judged falsely by the verdict: CONFORMING only
// when its truth is within the limit, NONCONFORMING only when beyond, UNDECIDED only where its
// value +- U holds the limit.
BendCheck check_bends(const FieldRun& run, const std::set<int>& unmeasurable, double bound,
                      const std::string& what) {
  BendCheck out;
  const auto& bends = run.report.bends();
  for (const parts::BendTruth& truth : run.bends) {
    const auto it = std::find_if(bends.begin(), bends.end(),
                                 [&](const v1::Bend& b) { return b.id() == truth.bend_id; });
    EXPECT_NE(it, bends.end()) << what << " bend " << truth.bend_id;
    if (it == bends.end()) continue;
    if (truth.hem) {
      EXPECT_FALSE(it->measurable()) << what << " bend " << truth.bend_id << " is a closed hem";
      EXPECT_TRUE(it->pass()) << what << ": a closed hem never fails the part by itself";
    }
    EXPECT_EQ(it->measured(), unmeasurable.count(truth.bend_id) == 0)
        << what << " bend " << truth.bend_id << ": " << it->status();
    if (!it->measured()) {
      EXPECT_FALSE(it->status().empty()) << what << " bend " << truth.bend_id << " says why not";
      std::printf("  %s bend %d (%.1f deg): %s\n", what.c_str(), truth.bend_id,
                  it->nominal_angle_deg(), it->status().c_str());
      continue;
    }
    ++out.measured;
    out.springback[truth.bend_id] = it->springback_deg();
    EXPECT_FALSE(it->end_tangents()) << what << " bend " << truth.bend_id << ": no flange curled";
    const double error = std::abs(it->springback_deg() - truth.springback_deg);
    out.worst = std::max(out.worst, error);
    EXPECT_LE(error, bound) << what << " bend " << truth.bend_id << ": measured "
                            << it->springback_deg() << ", truth " << truth.springback_deg;
    // The verdict's decision under the guard band (issue 41): never false against the truth;
    // UNDECIDED only where the measured value's interval +-U holds the limit.
    const double limit = it->angle_tolerance_deg();
    const double value = std::abs(it->springback_deg()), u = it->springback_uncertainty_deg();
    const bool within = std::abs(truth.springback_deg) <= limit;
    const std::string figures = what + " bend " + std::to_string(truth.bend_id) + ": " +
                                std::to_string(it->springback_deg()) + " +- " + std::to_string(u) +
                                " deg, truth " + std::to_string(truth.springback_deg) + ", limit " +
                                std::to_string(limit) + ", " + v1::Conformity_Name(it->decision());
    EXPECT_FALSE(it->decision() == v1::CONFORMING && !within) << "a false PASS: " << figures;
    EXPECT_FALSE(it->decision() == v1::NONCONFORMING && within) << "a false FAIL: " << figures;
    if (it->decision() == v1::UNDECIDED) {
      EXPECT_LE(value - u, limit) << figures;
      EXPECT_GE(value + u, limit) << figures;
      std::printf("  %s\n", figures.c_str());
    }
    EXPECT_EQ(it->pass(), it->decision() == v1::CONFORMING) << figures;
  }
  return out;
}

// The passes of these cases see what tells every part from its turned copy (tilted about the
// diagonal, or from below): the fit must find the part, never report it ambiguous. Only the
// cases that build the symmetric view (the side panel's notched wall edge-on) may.
bool expect_found(const FieldRun& run, const std::string& what) {
  EXPECT_FALSE(run.report.global_fit().ambiguous())
      << what << ": reported ambiguous (" << run.report.global_fit().orientation_decided_by()
      << ", ratio " << run.report.global_fit().orientation_ambiguity() << ")";
  return !run.report.global_fit().ambiguous();
}

TEST_P(ProductionPart, SpringbackOfEveryBend) {
  const PartExpectation& part = GetParam();
  const auto& cad = parts::testing::loaded_part(part.name);
  const FieldRun run = testing::run_field_case(cad, random_springback(cad, 11));
  ASSERT_TRUE(expect_found(run, part.name));
  const BendCheck check = check_bends(run, unmeasurable_by_construction(run, cad), 0.05, part.name);
  std::printf("%s: %d bends measured, worst springback error %.4f deg\n", part.name.c_str(),
              check.measured, check.worst);
  // The flanges are produced rigid: each flange of a measured bend is flat within the noise
  // (one skin of a solid: two passes may see both skins of a standing flange, a thickness
  // apart, and the shape is taken on one).
  const auto& bends = run.report.bends();
  std::set<int> fitted;
  for (const auto& b : bends)
    if (b.measured()) fitted.insert({b.segment_a(), b.segment_b()});
  for (const auto& seg : run.report.segments()) {
    if (!fitted.count(seg.id())) continue;
    EXPECT_LE(seg.flatness_rms_mm(), 0.03) << "segment " << seg.id();
    EXPECT_FALSE(seg.has_curl_radius_mm()) << "segment " << seg.id();
  }
  EXPECT_GE(check.measured, part.measurable_bends);
}

// Both skins of the sheet turn by the same angle at a bend: scanned from above and from below
// (the scanner's view flipped), the same produced part gives every measured bend its
// constructed springback, so the two sides agree. Accuracy, not memory: not under the
// sanitizers (the code paths are SpringbackOfEveryBend's).
TEST_P(ProductionPart, BothSidesGiveTheSameAngles) {
  if (testing::kUnderSanitizer) GTEST_SKIP() << "accuracy test, run without sanitizers";
  const PartExpectation& part = GetParam();
  const auto& cad = parts::testing::loaded_part(part.name);
  FieldScenario sc = random_springback(cad, 13);
  const FieldRun top_run = testing::run_field_case(cad, sc);
  sc.from_below = true;
  const FieldRun bottom_run = testing::run_field_case(cad, sc);
  ASSERT_TRUE(expect_found(top_run, part.name + " top"));
  ASSERT_TRUE(expect_found(bottom_run, part.name + " bottom"));
  const BendCheck top =
      check_bends(top_run, unmeasurable_by_construction(top_run, cad), 0.05, "top");
  const BendCheck bottom =
      check_bends(bottom_run, unmeasurable_by_construction(bottom_run, cad), 0.05, "bottom");
  double worst_pair = 0.0;
  for (const auto& [id, sb] : bottom.springback)
    if (top.springback.count(id))
      worst_pair = std::max(worst_pair, std::abs(sb - top.springback.at(id)));
  std::printf(
      "%s: top %d bends (worst %.4f deg), bottom %d bends (worst %.4f deg), "
      "largest top-bottom difference %.4f deg\n",
      part.name.c_str(), top.measured, top.worst, bottom.measured, bottom.worst, worst_pair);
  EXPECT_LE(worst_pair, 0.05);
  EXPECT_GE(top.measured, part.measurable_bends);
  EXPECT_GE(bottom.measured, part.measurable_from_below);
}

// The noisy case: sigma 0.05 mm, 2 % outliers, 10 % of the seen area missing. Every
// measured bend within 0.1 deg of its truth and judged right; the part fails (its springback
// reaches 3 deg).
TEST_P(ProductionPart, NoisyScanWithinOneTenth) {
  if (testing::kUnderSanitizer) GTEST_SKIP() << "accuracy test, run without sanitizers";
  const PartExpectation& part = GetParam();
  const auto& cad = parts::testing::loaded_part(part.name);
  FieldScenario sc = random_springback(cad, 17);
  sc.noise_mm = 0.05;
  sc.outliers = 0.02;
  sc.missing = 0.10;
  const FieldRun run = testing::run_field_case(cad, sc);
  ASSERT_TRUE(expect_found(run, part.name + " noisy"));
  // Measured 0.002-0.048 deg (side panel): 0.1 is about twice the worst.
  const BendCheck check = check_bends(run, unmeasurable_by_construction(run, cad), 0.1, "noisy");
  std::printf("%s noisy: %d bends measured, worst springback error %.4f deg\n", part.name.c_str(),
              check.measured, check.worst);
  EXPECT_GE(check.measured, part.measurable_noisy);
  bool beyond = false;
  for (const parts::BendTruth& truth : run.bends)
    beyond = beyond || (!truth.hem && std::abs(truth.springback_deg) > 1.0 + 0.1);
  if (beyond) {
    EXPECT_FALSE(run.report.verdict().pass());
  }
}

// As the station's laser driver delivers a scan: points only, the part facing the scanner
// (+z of the scan frame) within 30 deg.
TEST_P(ProductionPart, PointsOnlyScanFitsThePose) {
  const PartExpectation& part = GetParam();
  const auto& cad = parts::testing::loaded_part(part.name);
  FieldScenario sc;
  sc.springback_deg = {0.0};
  sc.scanner_normals = false;
  sc.pose = Eigen::Translation3d(40.0, -25.0, 300.0) *
            Eigen::AngleAxisd(0.5, Vec3(0.2, 0.3, 1.0).normalized());
  const FieldRun run = testing::run_field_case(cad, sc);
  const Transform& T = run.T_result_part;
  const double rotation_deg = Eigen::AngleAxisd(T.linear()).angle() * 180.0 / std::numbers::pi;
  std::printf("%s points only: rotation %.4f deg, residual %.4f mm, ambiguity %.3f\n",
              part.name.c_str(), rotation_deg, run.report.global_fit().rms_residual(),
              run.report.global_fit().orientation_ambiguity());
  // This view leaves the side panel's notched wall without a telling point (0): its half turn
  // fits as well, and the part must be reported ambiguous (a verdict reason, a PLC result code),
  // never turned silently.
  if (view_hides_the_asymmetry(part, run, cad)) {
    EXPECT_TRUE(run.report.global_fit().ambiguous()) << "turned silently or by chance";
    EXPECT_FALSE(run.report.verdict().pass());
    return;
  }
  ASSERT_TRUE(expect_found(run, part.name + " points only"));
  EXPECT_LE(rotation_deg, part.points_only_rotation_deg);
  EXPECT_LE(run.report.global_fit().rms_residual(), part.points_only_residual_mm);
}

// Points only, springback on every bend, the two passes tilted about the diagonal so that every
// wall is seen from both of its sides: each skin's points pair with that skin (the local fit's
// two layers, springback/local_fit.cpp), not all of a flange's with one. Before, the walls'
// fits settled between the skins (rms 1 mm) and their bends had no angle.
TEST_P(ProductionPart, PointsOnlyScanMeasuresEveryBend) {
  const PartExpectation& part = GetParam();
  const auto& cad = parts::testing::loaded_part(part.name);
  FieldScenario sc = random_springback(cad, 11);
  sc.scanner_normals = false;
  sc.pose = Eigen::Translation3d(40.0, -25.0, 300.0) *
            Eigen::AngleAxisd(0.5, Vec3(0.2, 0.3, 1.0).normalized());
  const FieldRun run = testing::run_field_case(cad, sc);
  ASSERT_TRUE(expect_found(run, part.name + " points only"));
  const BendCheck check =
      check_bends(run, unmeasurable_by_construction(run, cad), 0.05, part.name + " points only");
  std::printf("%s points only: %d bends measured, worst springback error %.4f deg\n",
              part.name.c_str(), check.measured, check.worst);
  EXPECT_GE(check.measured, part.measurable_bends);
}

// Issue 32: two fresh draws of the side panel (bench/accuracy_sweep --seed 99 --case 13 and
// --case 11; springback, pose and scan seed as drawn there) whose passes catch only a few points
// of its notched wall, the one feature that tells it from its half turn. Points only; the first
// at sigma 0.05 mm with 2 % outliers and 10 % missing, which the station reported ambiguous: the
// decisive points counted lone outliers, which lie far off one orientation by chance, against
// the notch's few points. A point now tells only with company (another within 2 mm), and 4
// points suffice instead of 10. The second draw, decided before, guards that it stays decided.
// The truth is the constructed pose: the half turn puts the panel some 800 mm off; the frame
// error allowed is that of points-only scans of solids (about 1.1 mm here, issue 32's open
// "poses under noise", docs/springback.md).
struct SidePanelDraw {
  std::uint64_t seed;
  double noise_mm, outliers, missing;
  std::vector<double> springback_deg;
  std::array<double, 12> pose;  // row-major 3 x 4, scan from part
};

TEST(SidePanelOrientation, FewNotchPointsDecideUnderNoise) {
  if (testing::kUnderSanitizer) GTEST_SKIP() << "accuracy test, run without sanitizers";
  const std::vector<SidePanelDraw> draws = {
      {35720,
       0.05,
       0.02,
       0.10,
       {1.5740969284193849, 2.2646302621035486, 2.9718486141487288, 0.39064425012374532,
        2.3118760121696145, 0.38730563281310876, 2.3855630594924118, 2.5845086745065378,
        2.4969222232083288, 2.0466729044119898, 0.49353667054571626, 0.38787612829522822,
        2.8508041160913637, 2.8111561906103031, 1.1825492183352158, 1.3576187661373949},
       {-0.84158931018638161, -0.25378100641101059, -0.47678363412036812, 230.94600932410447,
        0.34763432626115909, -0.93010565496212871, -0.11854891738189506, 476.64064279151978,
        -0.41337369072663588, -0.26551585902255259, 0.87098996574160115, 194.64416653434898}},
      {5576,
       0.02,
       0.0,
       0.0,
       {0, 2.6044926160703255, 0.25475998909335373, 0, 2.768155719785804, 1.6970966131495531,
        2.4561014719668659, 1.5051647829497106, 1.4233874845435808, 0.58260596767642836,
        1.1254562472794158, 1.2459422730970851, 1.9162540277987379, 1.6613041754848901,
        2.9346906687204513, 2.1532097013109213},
       {0.54088619446461417, 0.84055752258860472, -0.03008614061814192, 481.05782151898336,
        -0.76163680303220904, 0.47429809491447161, -0.44153221561668504, 352.88485428209106,
        -0.35686342612330485, 0.2617333917944174, 0.89674083586916375, -101.07819869086819}}};
  const auto& cad = parts::testing::loaded_part("openamr-MMP.00.00.00.003_Side_panel.step");
  for (const SidePanelDraw& d : draws) {
    FieldScenario sc;
    sc.seed = d.seed;
    sc.noise_mm = d.noise_mm;
    sc.outliers = d.outliers;
    sc.missing = d.missing;
    sc.springback_deg = d.springback_deg;
    sc.tilt_axis_deg = 45.0;
    sc.scanner_normals = false;
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 4; ++c)
        sc.pose.matrix()(r, c) = d.pose[static_cast<std::size_t>(4 * r + c)];
    const FieldRun run = testing::run_field_case(cad, sc);
    std::printf("side panel draw %llu: ambiguous %d, result frame off by %.4f mm\n",
                static_cast<unsigned long long>(d.seed), run.report.global_fit().ambiguous(),
                run.frame_error_mm);
    EXPECT_FALSE(run.report.global_fit().ambiguous()) << d.seed;
    EXPECT_LT(run.frame_error_mm, 1.5) << d.seed;
  }
}

INSTANTIATE_TEST_SUITE_P(Openamr, ProductionPart, ::testing::ValuesIn(expectations()),
                         [](const ::testing::TestParamInfo<PartExpectation>& param) {
                           std::string n;
                           for (char c : param.param.name)
                             if (std::isalnum(static_cast<unsigned char>(c))) n += c;
                           return n.substr(0, n.size() - 4);  // without "step"
                         });

}  // namespace
}  // namespace springscan::analysis
