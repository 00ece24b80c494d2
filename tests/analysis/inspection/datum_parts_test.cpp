// Datum (RPS) alignment end to end on sheet-metal parts this test models itself (issue 40): a
// bracket, a tray and a panel built as OpenCASCADE solids (simulators/parts/sheet_cutouts.hpp)
// with round holes and slots cut where the test puts them, 3-2-1 datums on the root flange (three
// pads, a hole, a second hole or a slot as the 2-way pin), every other flange sprung back 1-3 deg
// (the root flange keeps its CAD place: simulators/parts/produced_part.hpp), scanned one-sided,
// tilted or all round at sigma 0.02 mm, or 0.05 mm with 2 % outliers, and analysed by
// run_inspection from its own best fit. The datum features of the produced part sit at their
// nominal positions, so the true datum frame is the placement the test chose: the result frame
// times the placement must be the identity, at every datum and at the root flange's centroid.
#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <map>
#include <numbers>
#include <random>

#include "analysis/cad/model.hpp"
#include "analysis/cad/sampling.hpp"
#include "analysis/cad/segmentation.hpp"
#include "analysis/messages/alignment_proto.hpp"
#include "simulators/parts/laser_scan.hpp"
#include "simulators/parts/sheet_cutouts.hpp"
#include "tests/analysis/inspection/datum_truth.hpp"
#include "tests/analysis/matching/field_truth.hpp"
#include "tests/analysis/under_sanitizer.hpp"

namespace springscan::analysis {
namespace {

constexpr double kPadRadius = 3.0;

// A place on the root flange's seen skin: s along the flange from its start, y across (mm).
struct At {
  double s, y;
};

struct OwnPart {
  std::string name;
  parts::ProfileSpec spec;
  int root = 0;          // the flange index of the root (the largest)
  std::vector<At> pads;  // three
  At hole;               // B
  double hole_diameter = 0.0;
  At pin;  // C: a 2-way hole, or a slot whose long axis points at B
  double pin_diameter = 0.0;
  double pin_length = 0.0;  // > pin_diameter: a slot
};

// The root flange's frame: origin at its start on the reference skin, `along` it, its normal
// (the reference skin's, out of the material), in the CAD frame.
struct RootFrame {
  Vec3 origin, along, normal;
  Vec3 at(const At& a) const { return origin + a.s * along + a.y * Vec3::UnitY(); }
};

RootFrame root_frame(const OwnPart& p) {
  for (const parts::ProfileElement& e : parts::profile_path(p.spec)) {
    if (e.kind != parts::ProfileElement::Kind::kLine || e.flange_index != p.root) continue;
    const Eigen::Vector2d d = (e.end - e.start).normalized();
    return {parts::profile_to_3d(e.start, 0.0), parts::profile_to_3d(d, 0.0),
            parts::profile_to_3d(Eigen::Vector2d(-d.y(), d.x()), 0.0)};
  }
  return {};
}

std::vector<Datum> datums_of(const OwnPart& p) {
  const RootFrame f = root_frame(p);
  std::vector<Datum> out;
  for (std::size_t k = 0; k < p.pads.size(); ++k) {
    Datum d;
    d.name = "A" + std::to_string(k + 1);
    d.point = f.at(p.pads[k]);
    d.normal = f.normal;
    d.radius_mm = kPadRadius;
    out.push_back(d);
  }
  Datum b;
  b.name = "B";
  b.kind = DatumKind::kHole;
  b.point = f.at(p.hole);
  b.normal = f.normal;
  b.diameter_mm = p.hole_diameter;
  out.push_back(b);
  Datum c;
  c.name = "C";
  c.point = f.at(p.pin);
  c.normal = f.normal;
  const Vec3 to_b = (c.point - b.point).normalized();
  c.direction = f.normal.cross(to_b).normalized();  // across the line B-C: the turn about B
  c.diameter_mm = p.pin_diameter;
  c.kind = p.pin_length > p.pin_diameter ? DatumKind::kSlot : DatumKind::kHole;
  c.length_mm = c.kind == DatumKind::kSlot ? p.pin_length : 0.0;
  out.push_back(c);
  return out;
}

std::vector<parts::Cutout> cutouts_of(const OwnPart& p) {
  const RootFrame f = root_frame(p);
  const std::vector<Datum> d = datums_of(p);
  std::vector<parts::Cutout> out = {{d[3].point, f.normal, p.hole_diameter, 0.0, f.along}};
  out.push_back(
      {d[4].point, f.normal, p.pin_diameter, p.pin_length, (d[4].point - d[3].point).normalized()});
  return out;
}

parts::CadPart build(const OwnPart& p) {
  auto shape = parts::make_profile_with_cutouts(p.spec, cutouts_of(p));
  EXPECT_TRUE(shape) << shape.message();
  parts::CadPart cad;
  if (!shape) return cad;
  cad.shape = *shape;
  auto samples = sample_cad(cad.shape);
  EXPECT_TRUE(samples) << samples.message();
  if (samples) cad.model.samples = std::move(*samples);
  cad.model.segmentation = segment_cad(cad.shape);
  cad.model.face_count = cad.shape.face_count();
  cad.model.mesh = tessellation(cad.shape);
  return cad;
}

// Three parts: an L bracket (root 110 x 80, a 40 mm leg), a tray (root 140 x 90 between two
// 30 mm walls and a 12 mm lip), a panel (root 170 x 100, returns of 20 and 32 mm bent down: not
// symmetric, so that its best fit has one orientation); holes of 10,
// 8 and 12 mm, pins of 6 mm, a 6 x 14 slot and a 5 x 12 slot.
std::vector<OwnPart> own_parts() {
  OwnPart bracket{"bracket", {{110, 40}, {90}, {2.0}, 80.0, 2.0},
                  0,         {{12, 12}, {98, 14}, {55, 68}},
                  {30, 40},  10.0,
                  {85, 55},  6.0,
                  0.0};
  OwnPart tray{"tray",    {{30, 140, 30, 12}, {90, 90, -90}, {1.5, 1.5, 2.5}, 90.0, 1.5},
               1,         {{12, 10}, {128, 12}, {70, 78}},
               {40, 45},  8.0,
               {110, 45}, 6.0,
               14.0};
  OwnPart panel{"panel",   {{20, 170, 32}, {-90, -90}, {3.0, 3.0}, 100.0, 1.0},
                1,         {{12, 12}, {158, 12}, {85, 88}},
                {30, 70},  12.0,
                {140, 40}, 5.0,
                12.0};
  return {bracket, tray, panel};
}

struct View {
  std::string name;
  std::vector<Vec3> directions;  // the passes' view directions, in the root flange's frame
                                 // (x along it, y across, z its normal)
};

View view(const std::string& name) {
  const double s = std::sin(35.0 * std::numbers::pi / 180),
               c = std::cos(35.0 * std::numbers::pi / 180);
  if (name == "one-sided") return {name, {Vec3(s, 0, -c), Vec3(-s, 0, -c)}};
  if (name == "tilted") {
    const double d = s / std::sqrt(2.0);
    return {name, {Vec3(d, d, -c), Vec3(-d, -d, -c)}};
  }
  return {name, {Vec3(s, 0, -c), Vec3(-s, 0, -c), Vec3(0, s, c), Vec3(0, -s, c)}};  // all round
}

struct Outcome {
  double rotation_deg = 0.0, shift_mm = 0.0;  // the datum frame's error
  double best_rotation_deg = 0.0, best_shift_mm = 0.0;
  double floor_rotation_deg = 0.0, floor_shift_mm = 0.0;
  std::string measured_by;
};

Outcome run_case(const OwnPart& p, const parts::CadPart& cad, const View& v, bool noisy,
                 unsigned seed) {
  Outcome out;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> springback(1.0, 3.0);
  std::vector<double> sb;
  for (std::size_t k = 0; k < cad.model.segmentation.bends.size(); ++k)
    sb.push_back(springback(rng));
  auto part = parts::make_produced_part(cad.model, cad.shape, sb);
  EXPECT_TRUE(part) << part.message();
  if (!part) return out;
  const RootFrame f = root_frame(p);
  Mat3 R;  // root frame -> part frame
  R << f.along, Vec3::UnitY(), f.normal;
  parts::LaserScanSettings ls;
  ls.point_count =
      (testing::kUnderSanitizer ? 40'000 : 240'000) / static_cast<long>(v.directions.size());
  ls.noise_sigma_mm = noisy ? 0.05 : 0.02;
  ls.outlier_fraction = noisy ? 0.02 : 0.0;
  ls.line_direction = Vec3(0.35, 1.0, 0.0).normalized();
  ls.threads = 2;
  std::uniform_real_distribution<double> turn(-std::numbers::pi, std::numbers::pi),
      shift(-150, 150);
  ls.T_scan_part = Transform::Identity();
  ls.T_scan_part.linear() = Eigen::AngleAxisd(turn(rng), Vec3::UnitZ()).toRotationMatrix() *
                            Eigen::AngleAxisd(0.05, Vec3::UnitX()).toRotationMatrix();
  // In sequence, g++'s order (a call's arguments are unsequenced; tests/analysis/synthetic.hpp).
  const double y = shift(rng);
  const double x = shift(rng);
  ls.T_scan_part.translation() = Vec3(x, y, 300.0);
  PointCloud scan;
  if (!testing::scan_in_passes(*part, ls, R, v.directions, seed, scan)) return out;
  DatumAlignmentSettings ds;
  ds.datums = datums_of(p);
  v1::AnalysisSettings settings;
  to_proto(ds, settings.mutable_alignment());
  auto outcome = run_inspection(testing::exact_model(cad), scan, settings);
  EXPECT_TRUE(outcome) << outcome.message();
  if (!outcome) return out;
  const v1::Alignment& a = outcome->report.alignment();
  std::vector<Vec3> points;
  for (const Datum& d : ds.datums) points.push_back(d.point);
  const double length = p.spec.flange_lengths_mm[static_cast<std::size_t>(p.root)];
  points.push_back(f.at({0.5 * length, 0.5 * p.spec.width_mm}));  // the root's centroid
  std::tie(out.best_rotation_deg, out.best_shift_mm) = testing::datum_frame_error(
      testing::from_row_major(outcome->report.global_fit().transform()) * ls.T_scan_part, points);
  EXPECT_TRUE(a.achieved()) << p.name << " " << v.name << ": " << a.failure() << " (best fit "
                            << out.best_rotation_deg << " deg, " << out.best_shift_mm << " mm)";
  if (!a.achieved()) return out;
  std::tie(out.rotation_deg, out.shift_mm) =
      testing::datum_frame_error(testing::from_row_major(a.transform()) * ls.T_scan_part, points);
  std::tie(out.floor_rotation_deg, out.floor_shift_mm) =
      testing::datum_noise_floor(a, ds.datums, points);
  for (const auto& d : a.datums())
    out.measured_by += (out.measured_by.empty() ? "" : ", ") + d.name() + " " + d.measured_by();
  return out;
}

class DatumOwnPart : public ::testing::TestWithParam<int> {};

TEST_P(DatumOwnPart, FrameWithinBoundsOfTheConstruction) {
  struct Condition {
    std::string view;
    bool noisy;
  };
  std::vector<Condition> conditions = {
      {"one-sided", false}, {"tilted", true}, {"all-round", false}, {"one-sided", true}};
  if (testing::kUnderSanitizer) conditions.resize(1);
  unsigned seed = 10 * static_cast<unsigned>(GetParam());
  {
    const OwnPart p = own_parts()[static_cast<std::size_t>(GetParam())];
    // Kept for the process: testing::exact_model caches by the part's address.
    static std::map<int, parts::CadPart> built;
    const parts::CadPart& cad = built.emplace(GetParam(), build(p)).first->second;
    ASSERT_EQ(cad.model.segmentation.flanges.size(), p.spec.flange_lengths_mm.size()) << p.name;
    // SPRINGSCAN_DATUM_SEED: every condition's draws from that seed and the part's number (the
    // held-out runs).
    const char* held_out = std::getenv("SPRINGSCAN_DATUM_SEED");
    for (const Condition& c : conditions) {
      ++seed;
      if (held_out)
        seed = static_cast<unsigned>(std::strtoul(held_out, nullptr, 10)) +
               static_cast<unsigned>(GetParam());
      const Outcome o = run_case(p, cad, view(c.view), c.noisy, seed);
      const double rot_bound = std::max(c.noisy ? 0.01 : 0.005, 3.0 * o.floor_rotation_deg);
      const double shift_bound = std::max(c.noisy ? 0.04 : 0.02, 3.0 * o.floor_shift_mm);
      std::printf(
          "| %s | %s, %s | %.3f deg, %.3f mm | %.4f deg, %.4f mm | %.4f deg, %.4f mm | %s |\n",
          p.name.c_str(), c.view.c_str(), c.noisy ? "sigma 0.05, 2 % outliers" : "sigma 0.02",
          o.best_rotation_deg, o.best_shift_mm, o.rotation_deg, o.shift_mm, rot_bound, shift_bound,
          o.measured_by.c_str());
      EXPECT_LE(o.rotation_deg, rot_bound) << p.name << " " << c.view;
      EXPECT_LE(o.shift_mm, shift_bound) << p.name << " " << c.view;
    }
  }
}

// Under the sanitizers (5-15x slower) the bracket alone, one condition.
INSTANTIATE_TEST_SUITE_P(Parts, DatumOwnPart, ::testing::Range(0, testing::kUnderSanitizer ? 1 : 3),
                         [](const ::testing::TestParamInfo<int>& param) {
                           return std::string(param.param == 0   ? "Bracket"
                                              : param.param == 1 ? "Tray"
                                                                 : "Panel");
                         });

}  // namespace
}  // namespace springscan::analysis
