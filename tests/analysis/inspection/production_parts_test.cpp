// The production parts of ../shared/data/cad end to end: each part produced with a random
// springback on every bend, posed at random (any rotation, up to 500 mm), laser-scanned from
// one side in two passes tilted +-35 deg (200k points, sigma 0.02 mm), analysed by
// run_inspection with the exact CAD distance, as the station loads a part. Checked against the
// constructed truth: the result frame of the global fit, and every bend's springback.
#include "tests/simulators/parts/production_parts.hpp"

#include <gtest/gtest.h>

#include <cstdio>
#include <ostream>
#include <random>
#include <set>

#include "tests/analysis/matching/field_truth.hpp"
#include "tests/analysis/synthetic.hpp"

namespace springscan::analysis {
namespace {

using testing::FieldRun;
using testing::FieldScenario;

struct PartExpectation {
  std::string name;
  // Bends the two tilted passes can measure: both flanges seen. The others face along the tilt
  // axis (the scanner sees them edge-on) or are closed hems; they must say why they have no angle.
  int measurable_bends = 0;
  // The largest error of the result frame with no springback: rotation (deg), and shift of
  // the part's centroid (mm).
  double max_rotation_deg = 0.05;
  double max_shift_mm = 0.05;
  double max_residual_mm = 0.1;  ///< the fit's residual to the surface, sigma 0.02 mm
};

void PrintTo(const PartExpectation& part, std::ostream* os) { *os << part.name; }

const std::vector<PartExpectation>& expectations() {
  static const std::vector<PartExpectation> parts = {
      {"openamr-MMP.03.00.00.003_Motor_bracket.step", 4},
      // Its main flange and the 34 deg flanges leave a rotation about the bend lines weakly
      // fixed: 0.16 deg and 0.16 mm today (docs/alignment.md "Not yet right"); its bends are right
      // to 0.01.
      {"openamr-MMP.01.00.00.002_Cover_flange.step", 5, 0.2, 0.2, 0.15},
      {"openamr-MMP.00.00.00.003_Side_panel.step", 4},
      {"openamr-MMP.00.00.00.001_Front_panel.step", 2},
      {"nema-17-bracket.step", 1}};
  // Under the sanitizers (5-15x slower) one part: they look for memory errors and races.
  static const std::vector<PartExpectation> one(parts.begin(), parts.begin() + 1);
  return testing::kUnderSanitizer ? one : parts;
}

class ProductionPart : public ::testing::TestWithParam<PartExpectation> {};

TEST_P(ProductionPart, ZeroSpringbackFitsThePose) {
  const PartExpectation& part = GetParam();
  const auto& cad = parts::testing::loaded_part(part.name);
  std::mt19937 rng(7);
  FieldScenario sc;
  sc.springback_deg = {0.0};
  sc.pose = testing::random_motion(rng, 500.0);
  const FieldRun run = testing::run_field_case(cad, sc);
  // With no springback the produced part is the CAD part: the result frame is the identity.
  const Transform& T = run.T_result_part;
  Vec3 centroid = Vec3::Zero();
  for (const Vec3& p : cad.model.samples.points) centroid += p;
  centroid /= static_cast<double>(cad.model.samples.size());
  const double rotation_deg = Eigen::AngleAxisd(T.linear()).angle() * 180.0 / std::numbers::pi;
  const double shift_mm = (T * centroid - centroid).norm();
  std::printf("%s: rotation %.4f deg, shift at the centroid %.4f mm, residual %.4f mm\n",
              part.name.c_str(), rotation_deg, shift_mm, run.report.global_fit().rms_residual());
  EXPECT_LE(rotation_deg, part.max_rotation_deg);
  EXPECT_LE(shift_mm, part.max_shift_mm);
  EXPECT_FALSE(run.report.global_fit().ambiguous());
  EXPECT_LE(run.report.global_fit().rms_residual(), part.max_residual_mm);
}

TEST_P(ProductionPart, SpringbackOfEveryBend) {
  const PartExpectation& part = GetParam();
  const auto& cad = parts::testing::loaded_part(part.name);
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> springback(0.2, 3.0);
  FieldScenario sc;
  for (std::size_t i = 0; i < cad.model.segmentation.bends.size(); ++i)
    sc.springback_deg.push_back(springback(rng));
  sc.pose = testing::random_motion(rng, 500.0);
  const FieldRun run = testing::run_field_case(cad, sc);
  const auto& bends = run.report.bends();
  int measured = 0;
  double worst = 0.0;
  for (const parts::BendTruth& truth : run.bends) {
    const auto it = std::find_if(bends.begin(), bends.end(),
                                 [&](const v1::Bend& b) { return b.id() == truth.bend_id; });
    ASSERT_NE(it, bends.end()) << "bend " << truth.bend_id;
    if (truth.hem) {
      EXPECT_FALSE(it->measurable()) << "bend " << truth.bend_id << " is a closed hem";
      EXPECT_TRUE(it->pass()) << "a closed hem never fails the part by itself";
    }
    if (!it->measured()) {
      EXPECT_FALSE(it->status().empty()) << "bend " << truth.bend_id << " says why not";
      continue;
    }
    ++measured;
    EXPECT_FALSE(it->end_tangents()) << "bend " << truth.bend_id << ": no flange is curled";
    worst = std::max(worst, std::abs(it->springback_deg() - truth.springback_deg));
    EXPECT_NEAR(it->springback_deg(), truth.springback_deg, 0.05) << "bend " << truth.bend_id;
  }
  std::printf("%s: %d bends measured, worst springback error %.4f deg\n", part.name.c_str(),
              measured, worst);
  // The flanges are produced rigid: each flange of a measured bend is flat within the noise
  // (one skin of a solid: two passes may see both skins of a standing flange, a thickness
  // apart, and the shape is taken on one).
  std::set<int> fitted;
  for (const auto& b : bends)
    if (b.measured()) fitted.insert({b.segment_a(), b.segment_b()});
  for (const auto& seg : run.report.segments()) {
    if (!fitted.count(seg.id())) continue;
    EXPECT_LE(seg.flatness_rms_mm(), 0.03) << "segment " << seg.id();
    EXPECT_FALSE(seg.has_curl_radius_mm()) << "segment " << seg.id();
  }
  EXPECT_GE(measured, part.measurable_bends);
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
  // The side panel's half turn about its normal fits within 0.04 mm when the scan's normals
  // are estimated: then the part must be reported ambiguous (a verdict reason, a PLC result
  // code), never turned silently.
  if (run.report.global_fit().ambiguous()) {
    EXPECT_FALSE(run.report.verdict().pass());
    return;
  }
  EXPECT_LE(rotation_deg, part.max_rotation_deg);
  EXPECT_LE(run.report.global_fit().rms_residual(), part.max_residual_mm);
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
