// The global fit pinned by the part's boundary: profiles produced without springback, posed at
// random, laser-scanned whole in two tilted passes (field_truth.hpp), come back at the pose the
// test constructed along every direction, the profile's length included, which the surface alone
// leaves free; a scan of the middle only says that direction is free and how it was fixed.
#include "analysis/registration/boundary.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <vector>

#include "tests/analysis/matching/field_truth.hpp"
#include "tests/analysis/synthetic.hpp"

namespace springscan::analysis {
namespace {

using parts::ProfileSpec;

struct Profile {
  std::string name;
  ProfileSpec spec;
};

std::vector<Profile> profiles() {
  return {{"L", ProfileSpec{{70.0, 45.0}, {90.0}, {3.0}, 60.0, 0.0}},
          {"U", ProfileSpec{{35.0, 80.0, 25.0}, {90.0, 90.0}, {4.0, 4.0}, 60.0, 0.0}},
          {"Z", ProfileSpec{{40.0, 60.0, 30.0}, {80.0, -80.0}, {3.0, 3.0}, 60.0, 0.0}},
          {"hat", ProfileSpec{{30.0, 40.0, 60.0, 35.0, 25.0},
                              {90.0, -90.0, -90.0, 90.0},
                              {4.0, 4.0, 4.0, 4.0},
                              60.0,
                              0.0}}};
}

// The fit's error: T_result_part = T_cad_scan * T_scan_part is the identity for a perfect fit
// of a part made exactly as drawn.
struct PoseError {
  double translation_mm = 0.0;  ///< largest component
  double rotation_deg = 0.0;
};

PoseError pose_error(const testing::FieldRun& run, const Transform& pose) {
  const Transform E = testing::from_row_major(run.report.global_fit().transform()) * pose;
  PoseError e;
  e.translation_mm = E.translation().cwiseAbs().maxCoeff();
  e.rotation_deg = Eigen::AngleAxisd(E.linear()).angle() * 180.0 / std::numbers::pi;
  return e;
}

class BoundaryFit : public ::testing::TestWithParam<int> {};

TEST_P(BoundaryFit, ZeroSpringbackScannedWholeComesBackAtItsPose) {
  const Profile p = profiles()[static_cast<std::size_t>(GetParam())];
  const auto& cad = testing::field_part(p.name, &p.spec);
  const std::vector<unsigned> seeds =
      testing::kUnderSanitizer ? std::vector<unsigned>{1u} : std::vector<unsigned>{1u, 2u, 3u};
  for (unsigned seed : seeds) {
    std::mt19937 rng(400u + 10u * static_cast<unsigned>(GetParam()) + seed);
    testing::FieldScenario sc;
    sc.springback_deg = {0.0};
    sc.pose = testing::random_motion(rng, 200.0);
    sc.seed = seed;
    const testing::FieldRun run = testing::run_field_case(cad, sc);
    const PoseError e = pose_error(run, sc.pose);
    std::printf("%s seed %u: %.4f mm, %.5f deg\n", p.name.c_str(), seed, e.translation_mm,
                e.rotation_deg);
    EXPECT_LE(e.translation_mm, 0.02) << p.name << " seed " << seed;
    EXPECT_LE(e.rotation_deg, 0.005) << p.name << " seed " << seed;
  }
}

// Only the middle of the hat scanned (y in [15, 45] of its 60 mm): the surface and the ends both
// leave the length free. The report says so (direction, lengths, rule, a warning) and the fit
// is not moved along it.
TEST(BoundaryFit, MiddleOfAProfileScannedLeavesItsLengthFreeAndSaysSo) {
  const Profile p = profiles()[3];
  const auto& cad = testing::field_part(p.name, &p.spec);
  auto part = parts::make_produced_part(
      cad.model, cad.shape, std::vector<double>(cad.model.segmentation.bends.size(), 0.0));
  ASSERT_TRUE(part) << part.message();
  PointCloud scan;
  for (int side : {1, -1}) {
    parts::LaserScanSettings ls;
    ls.point_count = 60'000;
    ls.noise_sigma_mm = 0.02;
    ls.line_direction = Vec3(0.35, 1.0, 0.0).normalized();
    ls.view_direction = Vec3(side * 0.57, 0.0, -0.82).normalized();
    ls.seed = side + 5;
    auto pass = parts::laser_scan(*part, ls);
    ASSERT_TRUE(pass) << pass.message();
    for (std::size_t i = 0; i < pass->cloud.size(); ++i)
      if (pass->cad_points[i].y() >= 15.0 && pass->cad_points[i].y() <= 45.0)
        scan.points.push_back(pass->cloud.points[i]);
  }
  auto outcome = run_inspection(cad.model, scan, {});
  ASSERT_TRUE(outcome) << outcome.message();
  const auto& fit = outcome->report.global_fit();
  ASSERT_EQ(fit.free_directions_size(), 1);
  const auto& d = fit.free_directions(0);
  EXPECT_GT(std::abs(d.direction().y()), 0.999);  // the profile's length
  EXPECT_FALSE(d.pinned());
  EXPECT_EQ(d.shift_mm(), 0.0);
  EXPECT_NEAR(d.model_length_mm(), 60.0, 0.05);
  EXPECT_NEAR(d.scan_length_mm(), 30.0, 0.5);
  EXPECT_NE(d.rule().find("free"), std::string::npos) << d.rule();
  bool warned = false;
  for (const auto& w : outcome->report.warnings())
    warned |= w.find("left free") != std::string::npos;
  EXPECT_TRUE(warned);
}

// A whole-scan case reports the pinned direction with both lengths equal to the part's.
TEST(BoundaryFit, AWholeScanReportsTheLengthPinnedByTheEnds) {
  const Profile p = profiles()[1];
  const auto& cad = testing::field_part(p.name, &p.spec);
  testing::FieldScenario sc;
  sc.springback_deg = {1.0};
  std::mt19937 rng(77);
  sc.pose = testing::random_motion(rng, 200.0);
  const testing::FieldRun run = testing::run_field_case(cad, sc);
  const auto& fit = run.report.global_fit();
  ASSERT_EQ(fit.free_directions_size(), 1);
  EXPECT_TRUE(fit.free_directions(0).pinned());
  EXPECT_NEAR(fit.free_directions(0).model_length_mm(), 60.0, 0.05);
  EXPECT_NEAR(fit.free_directions(0).scan_length_mm(), 60.0, 0.1);
  EXPECT_NE(fit.free_directions(0).rule().find("pinned by the part's ends"), std::string::npos);
  // Along the length the fit is the part's: the motion of the part's centre along y.
  Vec3 centre = Vec3::Zero();
  for (const Vec3& q : cad.model.samples.points) centre += q;
  centre /= static_cast<double>(cad.model.samples.size());
  const Transform E = testing::from_row_major(fit.transform()) * sc.pose;
  EXPECT_LE(std::abs((E * centre - centre).y()), 0.02);
}

// A scan prepared once (BoundaryScan, as the pipeline's three pins share it) pins every fit as
// the scan given anew does, to the last bit: over several fits in turn, and with settings whose
// sample counts differ from the prepared ones (drawn anew then).
TEST(BoundaryFit, APreparedScanPinsAsTheScanGivenAnew) {
  const Profile p = profiles()[1];
  const auto& cad = testing::field_part(p.name, &p.spec);
  std::mt19937 rng(5);
  const Transform T_scan_part = testing::random_motion(rng, 100.0);
  std::vector<Vec3> scan;
  for (const Vec3& q : cad.model.samples.points) scan.push_back(T_scan_part * q);
  std::shuffle(scan.begin(), scan.end(), rng);
  const KdTree tree(cad.model.samples.points);
  BoundarySettings settings;
  settings.scan_points = scan.size() / 3;  // a strided sample, not every point
  const BoundaryScan prepared(scan, settings);
  for (const double slide_mm : {0.0, 0.4, -1.3}) {
    const Transform T = Eigen::Translation3d(0.0, slide_mm, 0.05) * T_scan_part.inverse();
    for (BoundarySettings s : {settings, BoundarySettings{}}) {
      const auto fresh = pin_to_boundary(scan, T, cad.model, tree, s);
      const auto reused = pin_to_boundary(prepared, T, cad.model, tree, s);
      ASSERT_TRUE(fresh && reused);
      EXPECT_TRUE(fresh->T_cad_scan.matrix() == reused->T_cad_scan.matrix());
      ASSERT_EQ(fresh->free_directions.size(), reused->free_directions.size());
      ASSERT_FALSE(fresh->free_directions.empty());  // the length: the ends were searched
      for (std::size_t k = 0; k < fresh->free_directions.size(); ++k) {
        EXPECT_EQ(fresh->free_directions[k].pinned, reused->free_directions[k].pinned);
        EXPECT_EQ(fresh->free_directions[k].shift_mm, reused->free_directions[k].shift_mm);
        EXPECT_EQ(fresh->free_directions[k].scan_length_mm,
                  reused->free_directions[k].scan_length_mm);
      }
      EXPECT_TRUE(slide_mm != 0.0 || fresh->free_directions[0].pinned);
    }
  }
}

std::string profile_name(const ::testing::TestParamInfo<int>& param) {
  return profiles()[static_cast<std::size_t>(param.param)].name;
}

INSTANTIATE_TEST_SUITE_P(Profiles, BoundaryFit, ::testing::Range(0, 4), profile_name);

}  // namespace
}  // namespace springscan::analysis
