// Datum (RPS) alignment end to end on the production solids whose largest flange has no round
// hole (issue 40): the openamr side panel and cover flange and the nema-17 bracket. Each is
// produced with its datum flange as the root (simulators/parts keeps the root where the CAD has
// it) and every other bend sprung back 1-3 deg, scanned one-sided or all round at sigma 0.02 mm,
// or 0.05 mm with 2 % outliers, and analysed by run_inspection from its own best fit. The 3-2-1
// datums come from the CAD's datum candidates on that flange: three pads on the skin the scanner
// sees, and round holes or slots as pins. The datum features of the produced part sit at their
// nominal positions, so the true datum frame is the placement the test chose: the result frame
// times the placement must be the identity, at every datum and at the flange's centroid.
#include <gtest/gtest.h>

#include <array>
#include <cstdio>
#include <cstdlib>
#include <numbers>
#include <random>

#include "analysis/cad/datum_features.hpp"
#include "analysis/messages/alignment_proto.hpp"
#include "tests/analysis/inspection/datum_truth.hpp"
#include "tests/analysis/matching/field_truth.hpp"
#include "tests/simulators/parts/production_parts.hpp"

namespace springscan::analysis {
namespace {

constexpr double kPadRadius = 2.5;
constexpr double kPadClearance = 4.0;  // from every other face: the pad lies on flat skin

// Which features pin the part in its flange's plane.
enum class Pins {
  kHoleAndPin,    // B a round hole (both directions), C a second one as a 2-way pin
  kHolesAndSlot,  // B and C round holes, each fixing the direction across the line B-C, and a
                  // slot fixing its own direction (along that line)
  kSlots,         // three slots: two fixing one direction (the turn), one the other
  kSlotAndEdges,  // a slot fixing the direction along the flange, and two points of the
                  // flange's free edge (`free_edge`) fixing the one across it and the turn
};

struct ProductionCase {
  std::string name, file;
  int root = 0;  // Flange::id of the datum flange; -1: the largest flange
  Pins pins = Pins::kHoleAndPin;
  long points = 400'000;  // over all passes: about 10 a mm^2 on the datum skin
  // The passes tilt about the flange's length (x of its frame), not across it: a narrow wall
  // seen straight on with the rest of the part edge-on fits turned half round as well.
  bool tilt_about_length = false;
  Vec3 free_edge = Vec3::Zero();  // kSlotAndEdges: out of the material across the free edge
  // Non-zero: the datum flange is the largest whose normal this is (`root` ignored; the flange
  // numbers depend on the segmentation's settings).
  Vec3 root_normal = Vec3::Zero();
};

void PrintTo(const ProductionCase& c, std::ostream* os) { *os << c.name; }

std::vector<ProductionCase> production_cases() {
  return {
      {"SidePanel", "openamr-MMP.00.00.00.003_Side_panel.step", 0, Pins::kSlotAndEdges, 1'200'000,
       true, -Vec3::UnitZ(), -Vec3::UnitY()},
      {"CoverFlange", "openamr-MMP.01.00.00.002_Cover_flange.step", 3, Pins::kHoleAndPin,
       1'200'000},
      {"Nema17Holes", "nema-17-bracket.step", 0, Pins::kHoleAndPin, 150'000},
      {"Nema17Slots", "nema-17-bracket.step", 1, Pins::kSlots, 150'000},
      // The parts with round holes on their largest flange (datum_alignment_test.cpp: one
      // view, sigma 0.02), here with the two views and noise levels.
      {"MotorBracket", "openamr-MMP.03.00.00.003_Motor_bracket.step", -1, Pins::kHoleAndPin,
       400'000},
      {"FrontPanel", "openamr-MMP.00.00.00.001_Front_panel.step", -1, Pins::kHoleAndPin, 600'000}};
}

// The datum flange's seen skin: its samples, and its triangles in the flange's plane (u, v).
struct RootSkin {
  std::vector<Vec3> skin;
  Vec3 normal = Vec3::UnitZ(), e1 = Vec3::UnitX(), e2 = Vec3::UnitY();
  std::vector<std::array<Eigen::Vector2d, 3>> triangles;

  Eigen::Vector2d uv(const Vec3& p) const { return {p.dot(e1), p.dot(e2)}; }
  bool inside(const Eigen::Vector2d& q) const {
    const auto cross = [](const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
      return a.x() * b.y() - a.y() * b.x();
    };
    for (const auto& t : triangles) {
      const double d0 = cross(t[1] - t[0], q - t[0]), d1 = cross(t[2] - t[1], q - t[1]),
                   d2 = cross(t[0] - t[2], q - t[2]);
      if ((d0 >= 0 && d1 >= 0 && d2 >= 0) || (d0 <= 0 && d1 <= 0 && d2 <= 0)) return true;
    }
    return false;
  }
};

RootSkin root_skin(const parts::CadPart& cad, const PadCandidate& root) {
  const PartModel& model = cad.model;
  const Flange& f = model.segmentation.flanges[static_cast<std::size_t>(root.flange_id)];
  const auto in_root = [&](int face) {
    return std::find(f.face_ids.begin(), f.face_ids.end(), face) != f.face_ids.end();
  };
  const auto on_skin = [&](const Vec3& p) {
    return std::abs((p - root.point).dot(root.normal)) < 1e-3;
  };
  RootSkin out;
  out.normal = root.normal;
  out.e1 = root.normal.unitOrthogonal();
  out.e2 = root.normal.cross(out.e1);
  for (std::size_t i = 0; i < model.samples.size(); ++i)
    if (in_root(model.samples.face_ids[i]) && model.samples.normals[i].dot(root.normal) > 0.999 &&
        on_skin(model.samples.points[i]))
      out.skin.push_back(model.samples.points[i]);
  const CadMesh& m = cad.shape.mesh();
  for (std::size_t t = 0; t < m.triangles.size(); ++t) {
    if (!in_root(m.triangle_faces[t])) continue;
    const auto& tri = m.triangles[t];
    const Vec3 &a = m.vertices[tri[0]], &b = m.vertices[tri[1]], &c = m.vertices[tri[2]];
    if (on_skin(a) && on_skin(b) && on_skin(c))
      out.triangles.push_back({out.uv(a), out.uv(b), out.uv(c)});
  }
  return out;
}

// Three pad points on the skin, spread (the farthest from the centre, the farthest from it, the
// largest triangle), each with the skin's material all round it within kPadClearance (clear of
// the sheet's edges, holes and bends: the skin's triangles cover the disc).
std::vector<Vec3> spread_pads(const RootSkin& s) {
  const auto clear_all_round = [&](const Vec3& p) {
    const Eigen::Vector2d c = s.uv(p);
    for (int k = 0; k < 24; ++k) {
      const double a = k * std::numbers::pi / 12;
      for (double r : {0.5 * kPadClearance, kPadClearance})
        if (!s.inside(c + r * Eigen::Vector2d(std::cos(a), std::sin(a)))) return false;
    }
    return true;
  };
  std::vector<Vec3> clear;
  for (const Vec3& p : s.skin)
    if (clear_all_round(p)) clear.push_back(p);
  EXPECT_GE(clear.size(), 3u);
  if (clear.size() < 3) return {};
  return testing::three_spread_points(clear);
}

Datum hole_datum(const std::string& name, const HoleCandidate& h) {
  Datum d;
  d.name = name;
  d.kind = DatumKind::kHole;
  d.point = h.centre;
  d.normal = h.axis;
  d.diameter_mm = h.diameter_mm;
  return d;
}

Datum slot_datum(const std::string& name, const SlotCandidate& s) {
  Datum d;
  d.name = name;
  d.kind = DatumKind::kSlot;
  d.point = s.centre;
  d.normal = s.axis;
  d.direction = s.direction;
  d.diameter_mm = s.width_mm;
  d.length_mm = s.length_mm;
  return d;
}

struct CaseDatums {
  std::vector<Datum> datums;
  Vec3 along = Vec3::UnitX(), normal = Vec3::UnitZ();  // the flange's frame (views)
  Vec3 centroid = Vec3::Zero();                        // of the flange's seen skin
  int root = 0;                                        // Flange::id
};

// The 3-2-1 datums of `c` from the CAD's candidates on its flange.
CaseDatums case_datums(const ProductionCase& c, const parts::CadPart& cad) {
  const auto candidates =
      datum_candidates(cad.shape, describe_faces(cad.shape), cad.model.segmentation);
  CaseDatums out;
  const auto root = std::find_if(  // the pads come largest first
      candidates.pads.begin(), candidates.pads.end(), [&](const PadCandidate& p) {
        if (!c.root_normal.isZero()) return p.normal.dot(c.root_normal) > 0.9998;
        return c.root < 0 || p.flange_id == c.root;
      });
  EXPECT_NE(root, candidates.pads.end());
  if (root == candidates.pads.end()) return out;
  out.normal = root->normal;
  out.root = root->flange_id;
  const RootSkin skin = root_skin(cad, *root);
  for (const Vec3& p : skin.skin) out.centroid += p / static_cast<double>(skin.skin.size());
  const std::vector<Vec3> pads = spread_pads(skin);
  for (std::size_t k = 0; k < pads.size(); ++k) {
    Datum d;
    d.name = "A" + std::to_string(k + 1);
    d.point = pads[k];
    d.normal = root->normal;
    d.radius_mm = kPadRadius;
    out.datums.push_back(d);
  }
  std::vector<HoleCandidate> holes;
  for (const HoleCandidate& h : candidates.holes)
    if (h.flange_id == out.root) holes.push_back(h);
  std::vector<SlotCandidate> slots;
  for (const SlotCandidate& s : candidates.slots)
    if (s.flange_id == out.root) slots.push_back(s);
  const auto farthest = [](const auto& list, const Vec3& from, auto score) {
    return *std::max_element(list.begin(), list.end(), [&](const auto& a, const auto& b) {
      return score(a.centre - from, a) < score(b.centre - from, b);
    });
  };
  if (c.pins == Pins::kSlots) {
    EXPECT_GE(slots.size(), 3u) << c.name;
    if (slots.size() < 3) return out;
    const SlotCandidate& s1 = slots.front();
    // The second fixing the same direction, farthest across it (the turn's lever); the third
    // fixing another direction.
    const SlotCandidate s2 = farthest(slots, s1.centre, [&](const Vec3& d, const SlotCandidate& s) {
      return std::abs(s.direction.dot(s1.direction)) > 0.999 ? d.cross(s1.direction).norm() : -1.0;
    });
    const SlotCandidate s3 = farthest(slots, s1.centre, [&](const Vec3& d, const SlotCandidate& s) {
      return std::abs(s.direction.dot(s1.direction)) < 0.1 ? d.norm() : -1.0;
    });
    out.datums.push_back(slot_datum("B", s1));
    out.datums.push_back(slot_datum("C", s2));
    out.datums.push_back(slot_datum("D", s3));
    out.along = (s2.centre - s1.centre).normalized();
    return out;
  }
  if (c.pins == Pins::kSlotAndEdges) {
    EXPECT_FALSE(slots.empty()) << c.name;
    if (slots.empty()) return out;
    // The slot farthest from the flange's middle: the part's near-symmetric twin of the flange
    // (the side panel's other wall) has none there, so a best fit turned half round is told.
    const SlotCandidate b =
        farthest(slots, out.centroid, [](const Vec3& d, const auto&) { return d.norm(); });
    out.datums.push_back(slot_datum("B", b));
    out.along = root->normal.cross(c.free_edge).normalized();
    // The free edge: the skin's farthest reach along free_edge; two points on it 40 % of the
    // skin's length either side of its centroid.
    double level = -1e9, lo = 1e9, hi = -1e9;
    for (const Vec3& p : skin.skin) {
      level = std::max(level, p.dot(c.free_edge));
      lo = std::min(lo, p.dot(out.along));
      hi = std::max(hi, p.dot(out.along));
    }
    for (const auto& t : skin.triangles)
      for (const Eigen::Vector2d& q : t) {
        const Vec3 p =
            q.x() * skin.e1 + q.y() * skin.e2 + root->point.dot(root->normal) * root->normal;
        level = std::max(level, p.dot(c.free_edge));
      }
    const double mid = 0.5 * (lo + hi), reach = 0.4 * (hi - lo);
    for (const double side : {-1.0, 1.0}) {
      Datum e;
      e.name = side < 0 ? "E1" : "E2";
      e.kind = DatumKind::kEdge;
      e.point = out.centroid + (mid + side * reach - out.centroid.dot(out.along)) * out.along +
                (level - out.centroid.dot(c.free_edge)) * c.free_edge;
      e.normal = root->normal;
      e.direction = c.free_edge;
      e.radius_mm = 10.0;
      out.datums.push_back(e);
    }
    return out;
  }
  EXPECT_GE(holes.size(), 2u) << c.name;
  if (holes.size() < 2) return out;
  const HoleCandidate& b = holes.front();  // the largest
  const HoleCandidate cc =
      farthest(holes, b.centre, [](const Vec3& d, const auto&) { return d.norm(); });
  out.along = (cc.centre - b.centre).normalized();
  const Vec3 across = root->normal.cross(out.along).normalized();
  Datum db = hole_datum("B", b), dc = hole_datum("C", cc);
  dc.direction = across;  // the turn about B
  if (c.pins == Pins::kHolesAndSlot) {
    db.direction = across;
    EXPECT_FALSE(slots.empty()) << c.name;
    if (slots.empty()) return out;
    // The slot fixing the direction along B-C, the farthest from B.
    const SlotCandidate d = farthest(slots, b.centre, [&](const Vec3& v, const SlotCandidate& s) {
      return std::abs(s.direction.dot(out.along)) > 0.9 ? v.norm() : -1.0;
    });
    EXPECT_GT(std::abs(d.direction.dot(out.along)), 0.9) << c.name;
    out.datums.push_back(db);
    out.datums.push_back(dc);
    out.datums.push_back(slot_datum("D", d));
    return out;
  }
  out.datums.push_back(db);
  out.datums.push_back(dc);
  return out;
}

// The passes' view directions in the flange's frame (x along it, y across, z its normal): two
// tilted +-35 deg about y, seeing the flange's datum skin (one-sided), or four, two from each
// side (all round).
std::vector<Vec3> view(bool all_round, bool tilt_about_length) {
  const double s = std::sin(35.0 * std::numbers::pi / 180),
               c = std::cos(35.0 * std::numbers::pi / 180);
  std::vector<Vec3> v = {Vec3(s, 0, -c), Vec3(-s, 0, -c)};
  if (all_round) v.insert(v.end(), {Vec3(0, s, c), Vec3(0, -s, c)});
  if (tilt_about_length)
    for (Vec3& d : v) d = Vec3(-d.y(), d.x(), d.z());  // turned 90 deg about the normal
  return v;
}

struct Outcome {
  double rotation_deg = 0.0, shift_mm = 0.0;  // the datum frame's error
  double best_rotation_deg = 0.0, best_shift_mm = 0.0;
  double floor_rotation_deg = 0.0, floor_shift_mm = 0.0;
  std::string measured_by;
};

// The produced part of `c` (every other bend sprung back 1-3 deg, drawn from `rng`) scanned in
// the passes of `all_round`, sigma 0.02 or (noisy) 0.05 with 2 % outliers, at a random placement
// (returned: the true scan-from-CAD pose); an empty scan on failure.
Transform scan_case(const ProductionCase& c, const parts::CadPart& cad, const CaseDatums& cd,
                    bool all_round, bool noisy, unsigned seed, PointCloud& scan) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> springback(1.0, 3.0);
  std::vector<double> sb;
  for (std::size_t k = 0; k < cad.model.segmentation.bends.size(); ++k)
    sb.push_back(springback(rng));
  parts::ProducedPartSettings ps;
  ps.root_flange = cd.root;
  auto part = parts::make_produced_part(cad.model, cad.shape, sb, ps);
  EXPECT_TRUE(part) << part.message();
  if (!part) return Transform::Identity();
  Mat3 R;  // flange frame -> part frame
  R << cd.along, cd.normal.cross(cd.along), cd.normal;
  const std::vector<Vec3> directions = view(all_round, c.tilt_about_length);
  parts::LaserScanSettings ls;
  ls.point_count = c.points / static_cast<long>(directions.size());
  ls.noise_sigma_mm = noisy ? 0.05 : 0.02;
  ls.outlier_fraction = noisy ? 0.02 : 0.0;
  ls.line_direction = R * Vec3(0.35, 1.0, 0.0).normalized();
  ls.threads = 2;
  std::uniform_real_distribution<double> turn(-std::numbers::pi, std::numbers::pi),
      shift(-150, 150);
  // In sequence, g++'s order (a call's arguments are unsequenced; tests/analysis/synthetic.hpp).
  const double a = turn(rng);
  const double y = shift(rng);
  const double x = shift(rng);
  ls.T_scan_part = Transform::Identity();
  ls.T_scan_part.linear() = Eigen::AngleAxisd(a, Vec3::UnitZ()).toRotationMatrix() *
                            Eigen::AngleAxisd(0.05, Vec3::UnitX()).toRotationMatrix() *
                            R.transpose();  // the flange faces the scanner
  ls.T_scan_part.translation() = Vec3(x, y, 300.0);
  if (!testing::scan_in_passes(*part, ls, R, directions, seed, scan)) scan = PointCloud{};
  return ls.T_scan_part;
}

Outcome run_case(const ProductionCase& c, const parts::CadPart& cad, const CaseDatums& cd,
                 bool all_round, bool noisy, unsigned seed) {
  Outcome out;
  PointCloud scan;
  const Transform T_scan_part = scan_case(c, cad, cd, all_round, noisy, seed, scan);
  if (scan.points.empty()) return out;
  DatumAlignmentSettings ds;
  ds.datums = cd.datums;
  v1::AnalysisSettings settings;
  to_proto(ds, settings.mutable_alignment());
  auto outcome = run_inspection(testing::exact_model(cad), scan, settings);
  EXPECT_TRUE(outcome) << outcome.message();
  if (!outcome) return out;
  const v1::Alignment& al = outcome->report.alignment();
  std::vector<Vec3> points;
  for (const Datum& d : ds.datums) points.push_back(d.point);
  points.push_back(cd.centroid);
  std::tie(out.best_rotation_deg, out.best_shift_mm) = testing::datum_frame_error(
      testing::from_row_major(outcome->report.global_fit().transform()) * T_scan_part, points);
  EXPECT_TRUE(al.achieved()) << c.name << (all_round ? " all-round" : " one-sided") << ": "
                             << al.failure() << " (best fit " << out.best_rotation_deg << " deg, "
                             << out.best_shift_mm << " mm)";
  if (!al.achieved()) return out;
  std::tie(out.rotation_deg, out.shift_mm) =
      testing::datum_frame_error(testing::from_row_major(al.transform()) * T_scan_part, points);
  std::tie(out.floor_rotation_deg, out.floor_shift_mm) =
      testing::datum_noise_floor(al, ds.datums, points);
  if (std::getenv("SPRINGSCAN_DATUM_DIAG")) {
    const Transform back =
        T_scan_part.inverse() * testing::from_row_major(al.transform()).inverse();
    for (const auto& d : al.datums()) {
      const Vec3 m(d.measured().x(), d.measured().y(), d.measured().z());
      const Vec3 n(d.nominal().x(), d.nominal().y(), d.nominal().z());
      const Vec3 e = back * m - n;
      std::printf("DIAG %s %s err (%.4f %.4f %.4f) pts %ld rms %.4f diam %.4f\n", d.name().c_str(),
                  d.measured_by().c_str(), e.x(), e.y(), e.z(), static_cast<long>(d.points()),
                  d.fit_rms_mm(), d.measured_diameter_mm());
    }
  }
  for (const auto& d : al.datums())
    out.measured_by += (out.measured_by.empty() ? "" : ", ") + d.name() + " " + d.measured_by() +
                       " (" + std::to_string(d.points()) + ")";
  return out;
}

class DatumProductionPart : public ::testing::TestWithParam<ProductionCase> {};

TEST_P(DatumProductionPart, FrameWithinBoundsOfTheConstruction) {
  const ProductionCase& c = GetParam();
  const parts::CadPart& cad = parts::testing::loaded_part(c.file);
  const CaseDatums cd = case_datums(c, cad);
  ASSERT_EQ(cd.datums.size(), c.pins == Pins::kHoleAndPin ? 5u : 6u) << c.name;
  for (const Datum& d : cd.datums)
    std::printf(
        "  %s %s at (%.2f %.2f %.2f), normal (%.3f %.3f %.3f), direction (%.3f %.3f %.3f)\n",
        d.name.c_str(), to_string(d.kind).c_str(), d.point.x(), d.point.y(), d.point.z(),
        d.normal.x(), d.normal.y(), d.normal.z(), d.direction.x(), d.direction.y(),
        d.direction.z());
  struct Condition {
    bool all_round, noisy;
  };
  std::vector<Condition> conditions = {{false, false}, {true, true}, {true, false}, {false, true}};
  if (testing::kUnderSanitizer) conditions.resize(1);
  if (const char* only = std::getenv("SPRINGSCAN_DATUM_CONDITION"))
    conditions = {conditions[std::strtoul(only, nullptr, 10)]};
  unsigned seed = 100 + 10 * static_cast<unsigned>(cd.root) + static_cast<unsigned>(c.pins);
  // SPRINGSCAN_DATUM_SEED: every condition's draws from that seed (the held-out runs).
  const char* held_out = std::getenv("SPRINGSCAN_DATUM_SEED");
  for (const Condition& k : conditions) {
    ++seed;
    if (held_out) seed = static_cast<unsigned>(std::strtoul(held_out, nullptr, 10));
    const Outcome o = run_case(c, cad, cd, k.all_round, k.noisy, seed);
    const double rot_bound = std::max(k.noisy ? 0.01 : 0.005, 3.0 * o.floor_rotation_deg);
    const double shift_bound = std::max(k.noisy ? 0.04 : 0.02, 3.0 * o.floor_shift_mm);
    std::printf(
        "| %s | %s, %s | %.3f deg, %.3f mm | %.4f deg, %.4f mm | %.4f deg, %.4f mm | %s |\n",
        c.name.c_str(), k.all_round ? "all-round" : "one-sided",
        k.noisy ? "sigma 0.05, 2 % outliers" : "sigma 0.02", o.best_rotation_deg, o.best_shift_mm,
        o.rotation_deg, o.shift_mm, rot_bound, shift_bound, o.measured_by.c_str());
    EXPECT_LE(o.rotation_deg, rot_bound) << c.name;
    EXPECT_LE(o.shift_mm, shift_bound) << c.name;
  }
}

// The side panel seen one-sided at sigma 0.05 with 2 % outliers, its best fit turned half round
// about each of the part's principal axes (the held-out miss of seed 20261207: the best fit lay
// so, and the surface favoured the turn back by 2.8 standard errors, not 5): the datums, which
// tell the halves apart (slot B has no twin on the other wall, the pads' skin faces away there),
// turn it back. The frame within the bound of the production cases. Dev seeds 7 and 8
// (SPRINGSCAN_DATUM_SEED replaces them: the held-out runs). Not under the sanitizers: a quarter
// of the points cost 6 s of CPU there (an eighth no longer measures slot B), and the plate's
// half-turn tests (registration/datum_test.cpp) run the same decision.
TEST(DatumProductionSidePanel, BestFitTurnedHalfRoundIsTurnedBack) {
  if (testing::kUnderSanitizer) GTEST_SKIP() << "6 s of CPU under the sanitizers";
  const ProductionCase c = production_cases().front();
  ASSERT_EQ(c.name, "SidePanel");
  const parts::CadPart& cad = parts::testing::loaded_part(c.file);
  const PartModel& model = testing::exact_model(cad);
  const CaseDatums cd = case_datums(c, cad);
  ASSERT_EQ(cd.datums.size(), 6u);
  Vec3 centroid = Vec3::Zero();
  for (const Vec3& p : model.samples.points)
    centroid += p / static_cast<double>(model.samples.size());
  Mat3 cov = Mat3::Zero();
  for (const Vec3& p : model.samples.points) cov += (p - centroid) * (p - centroid).transpose();
  const Mat3 axes = Eigen::SelfAdjointEigenSolver<Mat3>(cov).eigenvectors();
  std::vector<Vec3> points;
  for (const Datum& d : cd.datums) points.push_back(d.point);
  points.push_back(cd.centroid);
  DatumAlignmentSettings ds;
  ds.datums = cd.datums;
  std::vector<unsigned> seeds = {7, 8};
  if (const char* env = std::getenv("SPRINGSCAN_DATUM_SEED"))
    seeds = {static_cast<unsigned>(std::strtoul(env, nullptr, 10))};
  for (unsigned seed : seeds) {
    PointCloud scan;
    const Transform T_scan_part = scan_case(c, cad, cd, false, true, seed, scan);
    ASSERT_FALSE(scan.points.empty());
    for (int k = 0; k < 3; ++k) {
      Transform H = Transform::Identity();
      H.linear() = Eigen::AngleAxisd(std::numbers::pi, axes.col(k)).toRotationMatrix();
      H.translation() = centroid - H.linear() * centroid;
      const Transform start = H * T_scan_part.inverse();
      auto r = align_to_datums(scan.points, scan.normals, start, model, ds);
      ASSERT_TRUE(r) << r.message();
      ASSERT_TRUE(r->achieved) << "seed " << seed << ", turn " << k << ": " << r->failure;
      ASSERT_FALSE(r->rounds.empty());
      EXPECT_EQ(r->rounds.front().stage, "half turn") << "seed " << seed << ", turn " << k;
      v1::Alignment al;
      alignment_to_proto(start, &*r, &al);
      const auto [rot, shift] = testing::datum_frame_error(r->T_cad_scan * T_scan_part, points);
      const auto [floor_rot, floor_shift] = testing::datum_noise_floor(al, ds.datums, points);
      const double rot_bound = std::max(0.01, 3.0 * floor_rot);
      const double shift_bound = std::max(0.04, 3.0 * floor_shift);
      std::printf("seed %u, turn %d: %.4f deg, %.4f mm (bound %.4f deg, %.4f mm)\n", seed, k, rot,
                  shift, rot_bound, shift_bound);
      EXPECT_LE(rot, rot_bound) << "seed " << seed << ", turn " << k;
      EXPECT_LE(shift, shift_bound) << "seed " << seed << ", turn " << k;
    }
  }
}

// Under the sanitizers (5-15x slower) one small case: the nema-17 bracket on its holes.
std::vector<ProductionCase> cases() {
  std::vector<ProductionCase> all = production_cases();
  if (testing::kUnderSanitizer) {
    all.erase(std::remove_if(all.begin(), all.end(),
                             [](const ProductionCase& c) { return c.name != "Nema17Holes"; }),
              all.end());
    all.front().points = 40'000;
  }
  return all;
}

std::string case_name(const ::testing::TestParamInfo<ProductionCase>& param) {
  return param.param.name;
}

INSTANTIATE_TEST_SUITE_P(Production, DatumProductionPart, ::testing::ValuesIn(cases()), case_name);

}  // namespace
}  // namespace springscan::analysis
