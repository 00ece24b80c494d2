#include "simulators/parts/laser_scan.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <set>

#include "tests/simulators/parts/production_parts.hpp"

namespace springscan::parts {
namespace {

using testing::loaded_part;

constexpr double kDeg = std::numbers::pi / 180.0;
const char* const kMotorBracket = "openamr-MMP.03.00.00.003_Motor_bracket.step";
const char* const kSidePanel = "openamr-MMP.00.00.00.003_Side_panel.step";

ProducedPart produce(const std::string& name, double springback_deg = 1.5) {
  const auto& loaded = loaded_part(name);
  const std::vector<double> sb(loaded.model.segmentation.bends.size(), springback_deg);
  auto part = make_produced_part(loaded.model, loaded.shape, sb);
  EXPECT_TRUE(part) << part.message();
  return part ? *part : ProducedPart{};
}

// The flange faces of `part` whose produced outward normal faces a scanner looking along `view`.
std::set<int> facing_flange_faces(const ProducedPart& part, const PartModel& model,
                                  const Vec3& view, bool facing) {
  std::set<int> out;
  for (const Flange& flange : model.segmentation.flanges) {
    const Mat3 R = part.flange_transforms[static_cast<std::size_t>(flange.id)].linear();
    for (int f : flange.face_ids) {
      const Vec3 n = R * part.faces[static_cast<std::size_t>(f)].direction;
      if ((n.dot(view) < 0.0) == facing) out.insert(f);
    }
  }
  return out;
}

std::set<int> flange_faces_hit(const LaserScan& scan, const PartModel& model) {
  std::set<int> all, hit;
  for (const Flange& flange : model.segmentation.flanges)
    all.insert(flange.face_ids.begin(), flange.face_ids.end());
  for (int f : scan.cloud.face_ids) {
    if (all.count(f)) hit.insert(f);
  }
  return hit;
}

TEST(LaserScan, FromTheTopSeesNoBottomFace) {
  const auto& model = loaded_part(kMotorBracket).model;
  const ProducedPart part = produce(kMotorBracket);
  LaserScanSettings settings;
  settings.line_spacing_mm = 0.5;
  const auto scan = laser_scan(part, settings);
  ASSERT_TRUE(scan) << scan.message();
  ASSERT_GT(scan->cloud.size(), 10000u);
  const auto bottom = facing_flange_faces(part, model, settings.view_direction, false);
  for (int f : scan->cloud.face_ids) ASSERT_EQ(bottom.count(f), 0u) << "bottom face " << f;
  // Every point's true normal faces the scanner.
  for (const auto& n : scan->cloud.normals) ASSERT_LT(n.dot(settings.view_direction), 0.0);
  // The web's inner face and both brims' top faces are seen.
  EXPECT_EQ(flange_faces_hit(*scan, model).size(), 3u);
}

TEST(LaserScan, FromTheBottomSeesTheOtherSide) {
  const auto& model = loaded_part(kMotorBracket).model;
  const ProducedPart part = produce(kMotorBracket);
  LaserScanSettings top, bottom;
  bottom.view_direction = Vec3::UnitZ();
  const auto a = laser_scan(part, top);
  const auto b = laser_scan(part, bottom);
  ASSERT_TRUE(a && b);
  const auto seen_top = flange_faces_hit(*a, model), seen_bottom = flange_faces_hit(*b, model);
  ASSERT_FALSE(seen_bottom.empty());
  const auto facing_up = facing_flange_faces(part, model, Vec3::UnitZ(), true);
  for (int f : seen_bottom) {
    EXPECT_EQ(seen_top.count(f), 0u) << f;
    EXPECT_EQ(facing_up.count(f), 1u) << f;
  }
}

// Every production part, scanned from the top and from the bottom: each side sees only flange
// faces facing it, the two sides see disjoint faces, and every true normal faces the scanner.
class ScanBothSides : public ::testing::TestWithParam<std::string> {};

TEST_P(ScanBothSides, EachSideSeesOnlyItsFaces) {
  const auto& model = loaded_part(GetParam()).model;
  const ProducedPart part = produce(GetParam(), 1.0);
  std::set<int> seen[2];
  for (int side = 0; side < 2; ++side) {
    LaserScanSettings settings;
    settings.view_direction = Vec3(0.0, 0.0, side == 0 ? -1.0 : 1.0);
    settings.point_count = 60000;
    const auto scan = laser_scan(part, settings);
    ASSERT_TRUE(scan) << scan.message();
    EXPECT_NEAR(static_cast<double>(scan->cloud.size()), 60000.0, 6000.0);
    const auto away = facing_flange_faces(part, model, settings.view_direction, false);
    for (int f : scan->cloud.face_ids) ASSERT_EQ(away.count(f), 0u) << "face " << f;
    for (const auto& n : scan->cloud.normals) ASSERT_LT(n.dot(settings.view_direction), 0.0);
    seen[side] = flange_faces_hit(*scan, model);
    EXPECT_FALSE(seen[side].empty());
  }
  for (int f : seen[0]) EXPECT_EQ(seen[1].count(f), 0u) << "face " << f << " seen from both sides";
}

INSTANTIATE_TEST_SUITE_P(ProductionParts, ScanBothSides,
                         ::testing::ValuesIn(testing::production_parts()),
                         [](const auto& param_info) {
                           std::string name =
                               param_info.param.substr(0, param_info.param.rfind('.'));
                           if (name.rfind("openamr", 0) == 0)
                             name = name.substr(name.find('_') + 1);
                           std::replace(name.begin(), name.end(), '-', '_');
                           return name;
                         });

// Möller-Trumbore: does the ray from `o` along `d` meet triangle (a, b, c) beyond `t_min`?
bool ray_hits(const Vec3& o, const Vec3& d, const Vec3& a, const Vec3& b, const Vec3& c,
              double t_min) {
  const Vec3 e1 = b - a, e2 = c - a, p = d.cross(e2);
  const double det = e1.dot(p);
  if (std::abs(det) < 1e-14) return false;
  const Vec3 s = o - a;
  const double u = s.dot(p) / det;
  if (u < 0.0 || u > 1.0) return false;
  const Vec3 q = s.cross(e1);
  const double v = d.dot(q) / det;
  if (v < 0.0 || u + v > 1.0) return false;
  return e2.dot(q) / det > t_min;
}

bool visible_brute_force(const ProducedPart& part, const Vec3& p, const Vec3& view) {
  const auto& v = part.mesh.vertices;
  for (const auto& t : part.mesh.triangles) {
    if (ray_hits(p, -view, v[t[0]], v[t[1]], v[t[2]], 0.2)) return false;
  }
  return true;
}

// The hat seen from above at 40 degrees: one inner wall is seen, the other faces away, and the
// web lies partly in the shadow of the wall and brim; the scan holds exactly what a ray from
// the scanner reaches (brute force over every triangle).
TEST(LaserScan, OccludedRegionsAreAbsent) {
  const auto& model = loaded_part(kMotorBracket).model;
  const ProducedPart part = produce(kMotorBracket, 1.0);
  LaserScanSettings settings;
  settings.view_direction = Vec3(std::sin(40 * kDeg), 0.0, -std::cos(40 * kDeg));
  settings.line_direction = Vec3::UnitY();
  settings.line_spacing_mm = 0.4;
  const auto scan = laser_scan(part, settings);
  ASSERT_TRUE(scan) << scan.message();
  const Vec3 w = settings.view_direction;
  // Every point seen is reachable from the scanner (a sample of them, noise-free).
  for (std::size_t k = 0; k < scan->cloud.size(); k += 97) {
    ASSERT_TRUE(visible_brute_force(part, scan->cloud.points[k], w)) << k;
  }
  // The web's inner face: its seen share matches the brute-force share of its samples.
  const auto& web = model.segmentation.flanges[static_cast<std::size_t>(part.report.root_flange)];
  int inner = -1;
  for (int f : web.face_ids) {
    if (part.faces[static_cast<std::size_t>(f)].direction.z() > 0.5) inner = f;
  }
  ASSERT_GE(inner, 0);
  std::size_t samples = 0, lit = 0;
  for (std::size_t i = 0; i < part.samples.size(); ++i) {
    if (part.samples.face_ids[i] != inner) continue;
    ++samples;
    lit += visible_brute_force(part, part.samples.points[i], w) ? 1 : 0;
  }
  const double lit_share = static_cast<double>(lit) / static_cast<double>(samples);
  EXPECT_GT(lit_share, 0.5);
  EXPECT_LT(lit_share, 0.95);  // a real shadow
  const double area = part.faces[static_cast<std::size_t>(inner)].area_mm2;
  const double expected =
      lit_share * area * std::cos(40 * kDeg) / (scan->line_spacing_mm * scan->point_spacing_mm);
  const auto on_web = std::count(scan->cloud.face_ids.begin(), scan->cloud.face_ids.end(), inner);
  EXPECT_NEAR(static_cast<double>(on_web), expected, 0.03 * expected);
  // Of the walls, the inner face of the one facing the scanner is seen in full; the other
  // wall's inner face faces away, and its outer face lies in the shadow of its brim but for what
  // the brim's holes and notches let through (each of those points checked by brute force).
  const auto facing = facing_flange_faces(part, model, w, true);
  const auto points_on = [&](int f) {
    return std::count(scan->cloud.face_ids.begin(), scan->cloud.face_ids.end(), f);
  };
  const double unoccluded = 1008.0 * std::cos(50 * kDeg) / (0.4 * 0.4);  // a wall face, 1008 mm2
  for (int f : model.segmentation.flanges[0].face_ids) {
    if (!facing.count(f)) {
      EXPECT_EQ(points_on(f), 0) << f;
      continue;
    }
    EXPECT_LT(static_cast<double>(points_on(f)), 0.1 * unoccluded) << f;
    for (std::size_t k = 0; k < scan->cloud.size(); ++k) {
      if (scan->cloud.face_ids[k] == f) {
        ASSERT_TRUE(visible_brute_force(part, scan->cloud.points[k], w));
      }
    }
  }
  int seen = 0;
  for (int f : model.segmentation.flanges[1].face_ids) {
    if (facing.count(f)) {
      EXPECT_NEAR(static_cast<double>(points_on(f)), unoccluded, 0.03 * unoccluded) << f;
      ++seen;
    } else {
      EXPECT_EQ(points_on(f), 0) << f;
    }
  }
  EXPECT_EQ(seen, 1);
}

// The count comes out as asked on a large solid part. How fast: bench_production's
// BM_LaserScanSidePanel200k (no timing here: a loaded machine must not fail a test).
TEST(LaserScan, SidePanelPointCount) {
  const ProducedPart part = produce(kSidePanel, 2.0);
  LaserScanSettings settings;
  settings.point_count = 200000;
  settings.noise_sigma_mm = 0.02;
  const auto scan = laser_scan(part, settings);
  ASSERT_TRUE(scan) << scan.message();
  EXPECT_NEAR(static_cast<double>(scan->cloud.size()), 200000.0, 20000.0);
  // Missing areas: the count still comes out as asked.
  settings.missing_fraction = 0.1;
  const auto holed = laser_scan(part, settings);
  ASSERT_TRUE(holed);
  EXPECT_NEAR(static_cast<double>(holed->cloud.size()), 200000.0, 20000.0);
  EXPECT_GT(holed->missing, 5000);
}

TEST(LaserScan, NoiseOutliersAndPose) {
  const ProducedPart part = produce(kMotorBracket);
  LaserScanSettings settings;
  settings.noise_sigma_mm = 0.05;
  settings.outlier_fraction = 0.02;
  settings.T_scan_part = Transform(Eigen::AngleAxisd(0.7, Vec3(1, 2, 3).normalized()));
  settings.T_scan_part.translation() = Vec3(120, -40, 300);
  const auto scan = laser_scan(part, settings);
  ASSERT_TRUE(scan) << scan.message();
  const Vec3 w = settings.view_direction;
  double sum2 = 0.0;
  std::size_t inliers = 0;
  for (std::size_t k = 0; k < scan->cloud.size(); ++k) {
    const Vec3 p = settings.T_scan_part.inverse() * scan->cloud.points[k];
    const Vec3 truth = part.produced(scan->cad_points[k], scan->cloud.face_ids[k]);
    const Vec3 e = p - truth;
    ASSERT_LT((e - e.dot(w) * w).norm(), 1e-9);  // noise only along the ray
    if (scan->outlier[k]) continue;
    sum2 += e.squaredNorm();
    ++inliers;
  }
  EXPECT_NEAR(std::sqrt(sum2 / static_cast<double>(inliers)), 0.05, 0.0025);
  const double share =
      static_cast<double>(scan->outliers) / static_cast<double>(scan->cloud.size());
  EXPECT_NEAR(share, 0.02, 0.003);
}

TEST(LaserScan, DeterministicBySeedWhateverTheThreads) {
  const ProducedPart part = produce(kMotorBracket);
  LaserScanSettings settings;
  settings.noise_sigma_mm = 0.02;
  settings.outlier_fraction = 0.01;
  settings.missing_fraction = 0.1;
  settings.threads = 1;
  const auto a = laser_scan(part, settings);
  settings.threads = 0;
  const auto b = laser_scan(part, settings);
  settings.seed = 2;
  const auto c = laser_scan(part, settings);
  ASSERT_TRUE(a && b && c);
  ASSERT_EQ(a->cloud.size(), b->cloud.size());
  EXPECT_TRUE(a->cloud.points == b->cloud.points);
  EXPECT_FALSE(a->cloud.points == c->cloud.points);
}

TEST(LaserScan, TactileProbeGridOnTheTopSide) {
  const auto& model = loaded_part(kMotorBracket).model;
  const ProducedPart part = produce(kMotorBracket);
  ProbeSettings settings;
  settings.spacing_mm = 5.0;
  const auto probe = probe_grid(part, settings);
  ASSERT_TRUE(probe) << probe.message();
  const auto bottom = facing_flange_faces(part, model, settings.direction, false);
  EXPECT_GT(probe->cloud.size(), 200u);
  EXPECT_LT(probe->cloud.size(), 146u * 90u / 25u);
  for (std::size_t k = 0; k < probe->cloud.size(); ++k) {
    EXPECT_EQ(bottom.count(probe->cloud.face_ids[k]), 0u);
    EXPECT_LT(probe->cloud.normals[k].dot(settings.direction), -std::cos(60 * kDeg));
  }
}

TEST(LaserScan, RejectsBadSettings) {
  const ProducedPart part = produce(kMotorBracket);
  LaserScanSettings parallel_lines;
  parallel_lines.line_direction = parallel_lines.view_direction;
  EXPECT_FALSE(laser_scan(part, parallel_lines));
  LaserScanSettings no_spacing;
  no_spacing.line_spacing_mm = 0.0;
  EXPECT_FALSE(laser_scan(part, no_spacing));
  LaserScanSettings too_fine;
  too_fine.line_spacing_mm = 1e-4;
  EXPECT_FALSE(laser_scan(part, too_fine));
  EXPECT_FALSE(laser_scan(ProducedPart{}, LaserScanSettings{}));
}

}  // namespace
}  // namespace springscan::parts
