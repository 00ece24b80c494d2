// Datum (RPS) alignment end to end on production parts with holes: the part produced with
// springback on every bend (simulators/parts keeps its root flange, the largest, where the CAD
// has it), its 3-2-1 datums on that flange (three pads, a round hole, a second hole as a 2-way
// pin) taken from the CAD's datum candidates, laid on the station at a known placement (root
// flange toward the scanner, turned and shifted) and analysed by run_inspection. The datum
// features of the produced part sit at their nominal positions, so the constructed datum frame
// is the placement itself: the result frame times the placement must be the identity. The best
// fit, which spreads the springback over the whole part, is not.
#include <google/protobuf/text_format.h>
#include <gtest/gtest.h>

#include <cstdio>
#include <numbers>
#include <random>

#include "analysis/cad/datum_features.hpp"
#include "tests/analysis/inspection/datum_truth.hpp"
#include "tests/analysis/matching/field_truth.hpp"
#include "tests/simulators/parts/production_parts.hpp"

namespace springscan::analysis {
namespace {

using testing::FieldRun;
using testing::FieldScenario;

constexpr double kPadRadius = 3.0;

struct RootDatums {
  PadCandidate root;
  std::vector<Vec3> pads;
  HoleCandidate hole, pin;
};

// Three pad points on the root flange's skin, spread (the farthest from the centre, the farthest
// from it, the largest triangle), each clear of every other face by twice the pad's radius.
std::vector<Vec3> spread_pads(const PartModel& model, const PadCandidate& root) {
  const Flange& f = model.segmentation.flanges[static_cast<std::size_t>(root.flange_id)];
  const auto in_root = [&](int face) {
    return std::find(f.face_ids.begin(), f.face_ids.end(), face) != f.face_ids.end();
  };
  std::vector<Vec3> others, skin;
  for (std::size_t i = 0; i < model.samples.size(); ++i) {
    if (!in_root(model.samples.face_ids[i]))
      others.push_back(model.samples.points[i]);
    else if (model.samples.normals[i].dot(root.normal) > 0.999)
      skin.push_back(model.samples.points[i]);
  }
  const KdTree other_tree(others);
  std::vector<Vec3> clear;
  for (const Vec3& p : skin)
    if (std::sqrt(other_tree.nearest(p)->squared_distance) > 2.0 * kPadRadius) clear.push_back(p);
  EXPECT_GE(clear.size(), 3u);
  if (clear.size() < 3) return {};
  return testing::three_spread_points(clear);
}

// The laser looks down -z of the part's frame (simulators/parts/laser_scan.hpp): the datums go
// on the root flange's skin that faces +z, the candidates' skin or the other one a thickness
// away.
void on_scanned_skin(RootDatums& d) {
  if (d.root.normal.z() > 0.0) return;
  const double t = d.root.thickness_mm;
  d.root.point -= t * d.root.normal;
  d.root.normal = -d.root.normal;
  for (HoleCandidate* h : {&d.hole, &d.pin}) {
    h->centre -= t * h->axis;
    h->axis = -h->axis;
  }
}

RootDatums root_datums(const parts::CadPart& cad) {
  const auto candidates =
      datum_candidates(cad.shape, describe_faces(cad.shape), cad.model.segmentation);
  RootDatums d;
  d.root = candidates.pads.front();  // the largest flange: the produced part's root
  std::vector<HoleCandidate> holes;
  for (const HoleCandidate& h : candidates.holes)
    if (h.flange_id == d.root.flange_id) holes.push_back(h);
  EXPECT_GE(holes.size(), 2u) << "round holes on the root flange";
  if (holes.size() < 2) return d;
  // The main hole: the largest (the candidates come largest first); the pin: the farthest from it.
  d.hole = holes.front();
  d.pin = *std::max_element(holes.begin(), holes.end(), [&](const auto& a, const auto& b) {
    return (a.centre - d.hole.centre).norm() < (b.centre - d.hole.centre).norm();
  });
  on_scanned_skin(d);
  d.pads = spread_pads(cad.model, d.root);
  return d;
}

void put(const Vec3& v, v1::Vec3* out) {
  out->set_x(v.x());
  out->set_y(v.y());
  out->set_z(v.z());
}

v1::AnalysisSettings datum_settings(const RootDatums& d) {
  v1::AnalysisSettings s;
  auto& datums = *s.mutable_alignment();
  for (std::size_t k = 0; k < d.pads.size(); ++k) {
    v1::Datum& pad = *datums.add_datums();
    pad.set_name(std::string(1, 'A') += std::to_string(k + 1));
    pad.set_kind(v1::Datum::PAD);
    put(d.pads[k], pad.mutable_point());
    put(d.root.normal, pad.mutable_normal());
    pad.set_radius_mm(kPadRadius);
  }
  for (const HoleCandidate* h : {&d.hole, &d.pin}) {
    v1::Datum& hole = *datums.add_datums();
    hole.set_name(h == &d.hole ? "B" : "C");
    hole.set_kind(v1::Datum::HOLE);
    put(h->centre, hole.mutable_point());
    put(h->axis, hole.mutable_normal());
    hole.set_diameter_mm(h->diameter_mm);
    // The 2-way pin fixes the direction across the line between the holes: the turn about
    // the axis.
    if (h == &d.pin)
      put(h->axis.cross(d.pin.centre - d.hole.centre).normalized(), hole.mutable_direction());
  }
  return s;
}

// On the station, in the scanner's frame: turned about z, a little tilted, shifted (the laser's
// view is fixed in the part's frame; points-only scans want +z up).
Transform placement(std::mt19937& rng) {
  std::uniform_real_distribution<double> turn(-std::numbers::pi, std::numbers::pi), tilt(-0.1, 0.1),
      shift(-200.0, 200.0);
  // Drawn in sequence, in g++'s order (an operator's operands and a call's arguments are
  // unsequenced: clang placed the parts elsewhere; tests/analysis/synthetic.hpp).
  const double a = turn(rng);
  const double b = tilt(rng);
  const double y = shift(rng);
  const double x = shift(rng);
  Transform T = Transform::Identity();
  T.linear() = (Eigen::AngleAxisd(b, Vec3::UnitX()) * Eigen::AngleAxisd(a, Vec3::UnitZ()))
                   .toRotationMatrix();
  T.translation() = Vec3(x, y, 300.0);
  return T;
}

struct FrameError {
  double rotation_deg = 0.0, shift_mm = 0.0;  // the shift: the largest at a datum
};

FrameError frame_error(const Transform& E, const RootDatums& d) {
  FrameError e;
  e.rotation_deg = Eigen::AngleAxisd(E.linear()).angle() * 180.0 / std::numbers::pi;
  std::vector<Vec3> points = d.pads;
  points.push_back(d.hole.centre);
  points.push_back(d.pin.centre);
  for (const Vec3& p : points) e.shift_mm = std::max(e.shift_mm, (E * p - p).norm());
  return e;
}

class DatumPart : public ::testing::TestWithParam<std::string> {};

TEST_P(DatumPart, DatumFrameIsTheConstructedOne) {
  const auto& cad = parts::testing::loaded_part(GetParam());
  const RootDatums d = root_datums(cad);
  ASSERT_EQ(d.pads.size(), 3u);
  std::mt19937 rng(23);
  std::uniform_real_distribution<double> springback(0.5, 3.0);
  FieldScenario sc;
  for (std::size_t i = 0; i < cad.model.segmentation.bends.size(); ++i)
    sc.springback_deg.push_back(springback(rng));
  sc.pose = placement(rng);
  std::string config;  // the datum list as a part's config writes it (docs/alignment.md)
  google::protobuf::TextFormat::PrintToString(datum_settings(d), &config);
  std::printf("%s", config.c_str());
  const FieldRun run = testing::run_field_case(cad, sc, datum_settings(d));
  ASSERT_EQ(run.report.alignment().method(), "datum");
  const FrameError datum = frame_error(run.T_result_part, d);
  const FrameError best =
      frame_error(testing::from_row_major(run.report.global_fit().transform()) * sc.pose, d);
  std::printf("%s: best fit %.4f deg %.4f mm, datum frame %.5f deg %.5f mm (%d passes)\n",
              GetParam().c_str(), best.rotation_deg, best.shift_mm, datum.rotation_deg,
              datum.shift_mm, run.report.alignment().passes());
  EXPECT_LE(datum.rotation_deg, 0.005);
  EXPECT_LE(datum.shift_mm, 0.01);
  for (const auto& datum_result : run.report.alignment().datums()) {
    std::printf("  %s %s: %lld points, rms %.4f, residual %.5f mm, best fit's %.4f mm\n",
                datum_result.name().c_str(), datum_result.kind().c_str(),
                static_cast<long long>(datum_result.points()), datum_result.fit_rms_mm(),
                datum_result.residual_mm(), datum_result.best_fit_residual_mm());
    EXPECT_LE(datum_result.residual_mm(), 1e-4) << datum_result.name() << ": 3-2-1 is exact";
  }
  EXPECT_NEAR(run.report.alignment().datums(3).measured_diameter_mm(), d.hole.diameter_mm, 0.01);
  // The deviation at the datum pads: zero within the noise (sigma 0.02 mm along the rays).
  for (const Vec3& pad : d.pads) {
    double sum = 0.0, sum2 = 0.0;
    int n = 0;
    for (std::size_t i = 0; i < run.scan_cad_points.size(); ++i) {
      const Vec3 v = run.scan_cad_points[i] - pad;
      if (std::abs(v.dot(d.root.normal)) > 0.01 || v.norm() > kPadRadius) continue;
      sum += run.deviation[i], sum2 += run.deviation[i] * run.deviation[i], ++n;
    }
    ASSERT_GT(n, 30);
    const double mean = sum / n, rms = std::sqrt(sum2 / n);
    std::printf("  pad: %d points, mean deviation %.4f mm, rms %.4f mm\n", n, mean, rms);
    EXPECT_LE(std::abs(mean), 3.0 * 0.02 / std::sqrt(static_cast<double>(n)) + 0.002);
    EXPECT_LE(rms, 0.03);
  }
}

// A datum the scan does not have (a hole where the part has none): the report is written in the
// best-fit frame, the alignment marked not achieved with the datum named and why, and the
// verdict fails: never a silent fallback to the best fit.
TEST_P(DatumPart, UnmeasurableDatumFailsTheVerdict) {
  const auto& cad = parts::testing::loaded_part(GetParam());
  RootDatums d = root_datums(cad);
  ASSERT_EQ(d.pads.size(), 3u);
  d.pin.centre = d.pads[1];  // solid material there
  auto part = parts::make_produced_part(
      cad.model, cad.shape, std::vector<double>(cad.model.segmentation.bends.size(), 1));
  ASSERT_TRUE(part) << part.message();
  std::mt19937 rng(5);
  parts::LaserScanSettings ls;
  ls.point_count = 40'000;
  ls.noise_sigma_mm = 0.02;  // a noise-free scan leaves the bends' flange fits undecided
  ls.T_scan_part = placement(rng);
  PointCloud scan;
  for (double side : {1.0, -1.0}) {  // two passes tilted +-35 deg, as on the station
    ls.view_direction = Vec3(side * 0.57, 0.0, -0.82).normalized();
    auto pass = parts::laser_scan(*part, ls);
    ASSERT_TRUE(pass) << pass.message();
    scan.points.insert(scan.points.end(), pass->cloud.points.begin(), pass->cloud.points.end());
  }
  // Tolerances no part of this scan comes near: the datum alone must fail the verdict (never a
  // PASS); every other reason is undecided (a bend the two passes do not measure), none fails.
  v1::AnalysisSettings settings = datum_settings(d);
  v1::VerdictSettings& v = *settings.mutable_verdict();
  v.set_tolerance_mm(50.0);
  v.set_angle_tolerance_deg(45.0);
  v.set_min_coverage(0.0);
  v.set_max_fit_rms_mm(50.0);
  v.set_decision_rule(v1::VerdictSettings::SIMPLE);
  auto out = run_inspection(testing::exact_model(cad), scan, settings);
  ASSERT_TRUE(out) << out.message();
  const v1::Alignment& alignment = out->report.alignment();
  EXPECT_FALSE(alignment.achieved());
  EXPECT_EQ(alignment.method(), "best_fit");
  EXPECT_EQ(alignment.failed_datum(), "C");
  EXPECT_NE(alignment.failure().find("datum 'C' (hole) cannot be measured"), std::string::npos)
      << alignment.failure();
  for (int k = 0; k < 16; ++k)
    EXPECT_EQ(alignment.transform(k), out->report.global_fit().transform(k));
  EXPECT_FALSE(out->report.verdict().pass());
  EXPECT_EQ(out->report.verdict().decision(), v1::Verdict::FAIL);
  ASSERT_GT(out->report.verdict().reasons_size(), 0);
  for (int k = 0; k + 1 < out->report.verdict().reasons_size(); ++k) {
    const std::string& reason = out->report.verdict().reasons(k);
    EXPECT_EQ(reason.substr(reason.size() - std::min<std::size_t>(reason.size(), 11)),
              "(undecided)")
        << reason;
  }
  EXPECT_NE(
      out->report.verdict().reasons(out->report.verdict().reasons_size() - 1).find("datum 'C'"),
      std::string::npos);
}

// Under the sanitizers (5-15x slower) one part: they look for memory errors and races.
std::vector<std::string> datum_parts() {
  std::vector<std::string> parts = {"openamr-MMP.03.00.00.003_Motor_bracket.step",
                                    "openamr-MMP.00.00.00.001_Front_panel.step"};
  if (testing::kUnderSanitizer) parts.resize(1);
  return parts;
}

INSTANTIATE_TEST_SUITE_P(Openamr, DatumPart, ::testing::ValuesIn(datum_parts()),
                         [](const ::testing::TestParamInfo<std::string>& param) {
                           return param.param.find("Front") != std::string::npos ? "FrontPanel"
                                                                                 : "MotorBracket";
                         });

}  // namespace
}  // namespace springscan::analysis
