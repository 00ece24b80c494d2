// Near-symmetric parts: the global fit compares every distinct orientation on the
// same points by the same converged robust error, finds the right one of a part whose two
// orientations differ by a few millimetres of flange, and calls a part ambiguous only when the
// scan cannot tell two different answers apart.
#include "analysis/registration/orientation.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>
#include <string>

#include "analysis/registration/global_fit.hpp"
#include "simulators/parts/laser_scan.hpp"
#include "simulators/parts/sheet_part.hpp"
#include "tests/analysis/synthetic.hpp"
#include "tests/analysis/under_sanitizer.hpp"
#include "tests/simulators/parts/production_parts.hpp"

namespace springscan::analysis {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

// A pose of the part in the scanner frame near a half turn about part axis `axis` (0, 1, 2):
// off by up to 10 degrees about a random axis and up to 200 mm away.
Transform near_half_turn(std::mt19937& rng, int axis) {
  std::normal_distribution<double> g;
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const Vec3 wobble_axis = testing::draw_vec3(g, rng).normalized();
  const Mat3 R = Eigen::AngleAxisd(10.0 * kDeg * u(rng), wobble_axis).toRotationMatrix() *
                 Eigen::AngleAxisd(std::numbers::pi, Vec3::Unit(axis)).toRotationMatrix();
  Transform T = Transform::Identity();
  T.linear() = R;
  T.translation() = 200.0 * testing::draw_vec3(u, rng);
  return T;
}

double rotation_error_deg(const Transform& a, const Transform& b) {
  return Eigen::AngleAxisd(a.linear() * b.linear().transpose()).angle() / kDeg;
}

// A hat whose last brim is longer than the first by `extra_mm`.
ProfileSpec uneven_hat(double extra_mm) {
  ProfileSpec spec = hat_profile(25, 30, 40, 60, 4);
  spec.width_mm = 80;
  spec.flange_lengths_mm.back() += extra_mm;
  return spec;
}

GlobalFitSettings quick_settings() {
  GlobalFitSettings s;
  s.icp.max_iterations = 30;
  return s;
}

TEST(Orientation, UnevenHatIsFoundFromEveryHalfTurn) {
  std::mt19937 rng(161);
  int right = 0, trials = 0;
  // Under a sanitizer one unevenness of the three (the same code runs for each).
  const std::vector<double> extras =
      testing::kUnderSanitizer ? std::vector<double>{4.0} : std::vector<double>{3.0, 4.0, 5.0};
  for (double extra : extras) {
    const ProfileSpec spec = uneven_hat(extra);
    const PointCloud model = testing::sample_profile(spec, 40000, 7);
    const KdTree tree(model.points);
    for (int axis = 0; axis < 3; ++axis)
      for (int k = 0; k < 2; ++k) {
        ScanSimulationSettings st;
        st.point_count = 8000;
        st.noise_sigma_mm = 0.02;
        st.T_scan_part = near_half_turn(rng, axis);
        st.seed = static_cast<std::uint64_t>(100 + trials);
        const auto scan = simulate_scan(spec, std::vector<double>(4, 0.0), st);
        ASSERT_TRUE(scan.ok()) << scan.message();
        auto fit = global_fit(scan->points, tree, model.normals, quick_settings());
        ASSERT_TRUE(fit) << fit.message();
        ++trials;
        const Transform truth = st.T_scan_part.inverse();
        const double err = rotation_error_deg(fit->T_cad_scan, truth);
        if (err < 0.1) ++right;
        EXPECT_LT(err, 0.1) << "extra " << extra << " axis " << axis << " k " << k;
        EXPECT_FALSE(fit->ambiguous)
            << "extra " << extra << " ratio " << fit->orientation.ambiguity;
        // The in-profile translation (x, z): the width direction (y) is the boundary's business.
        const Vec3 dt = fit->T_cad_scan.translation() - truth.translation();
        EXPECT_LT(std::hypot(dt.x(), dt.z()), 0.05) << "extra " << extra << " axis " << axis;
      }
  }
  EXPECT_EQ(right, trials);
}

TEST(Orientation, SymmetricHatIsNotAmbiguous) {
  const ProfileSpec spec = uneven_hat(0.0);
  const PointCloud model = testing::sample_profile(spec, 40000, 7);
  const KdTree tree(model.points);
  std::mt19937 rng(162);
  ScanSimulationSettings st;
  st.point_count = 8000;
  st.T_scan_part = near_half_turn(rng, 2);
  const auto scan = simulate_scan(spec, std::vector<double>(4, 0.0), st);
  ASSERT_TRUE(scan.ok()) << scan.message();
  auto fit = global_fit(scan->points, tree, model.normals, quick_settings());
  ASSERT_TRUE(fit) << fit.message();
  EXPECT_FALSE(fit->ambiguous);
  // Either orientation is the same answer: the other one is either clearly worse on this scan or
  // recognised as the model's symmetry (orientation.symmetric_model); never ambiguous.
  EXPECT_LT(rms_nearest_distance(scan->points, fit->T_cad_scan, tree, 0.0), 0.5);
}

// A flat plate with a hole off centre, scanned with the hole covered: the scan fits the plate and
// the plate turned end for end equally well, but the two are different answers (the hole).
TEST(Orientation, IndistinguishableOrientationsAreAmbiguous) {
  std::vector<Vec3> plate, normals, scan;
  for (double x = 0; x <= 120; x += 0.5)
    for (double y = 0; y <= 60; y += 0.5) {
      if (std::hypot(x - 30, y - 30) >= 8.0) plate.emplace_back(x, y, 0.0);
      scan.emplace_back(x, y, 0.0);
    }
  normals.assign(plate.size(), Vec3::UnitZ());
  const KdTree tree(plate);
  Transform turned = Transform::Identity();  // half turn about z through the plate's middle
  turned.linear() = Eigen::AngleAxisd(std::numbers::pi, Vec3::UnitZ()).toRotationMatrix();
  turned.translation() = Vec3(120, 60, 0);
  IcpSettings icp;
  icp.max_iterations = 5;
  auto choice =
      choose_orientation(scan, tree, normals, {Transform::Identity(), turned}, {}, icp, 1);
  ASSERT_TRUE(choice) << choice.message();
  ASSERT_EQ(choice->candidates.size(), 2u);
  EXPECT_FALSE(choice->symmetric_model);  // the hole is off centre
  EXPECT_GT(choice->ambiguity, 0.9);
  EXPECT_TRUE(choice->ambiguous);
  // Without the hole the plate is symmetric: the same answer, not ambiguous.
  std::vector<Vec3> whole = scan;
  const KdTree whole_tree(whole);
  auto same = choose_orientation(scan, whole_tree, std::vector<Vec3>(whole.size(), Vec3::UnitZ()),
                                 {Transform::Identity(), turned}, {}, icp, 1);
  ASSERT_TRUE(same) << same.message();
  EXPECT_TRUE(same->symmetric_model);
  EXPECT_FALSE(same->ambiguous);
}

// A symmetric model fits an orientation and its turned copy equally well; which scored lowest
// followed the scan's point order (the demo hat, reversed, came out half turned, its bends
// numbered from the other end). The answer is the one nearest the nominal pose (identity),
// whatever order the candidates come in.
TEST(Orientation, SymmetricModelTakesTheOrientationNearestNominal) {
  std::vector<Vec3> plate;
  for (double x = 0; x <= 120; x += 0.5)
    for (double y = 0; y <= 60; y += 0.5) plate.emplace_back(x, y, 0.0);
  const std::vector<Vec3> normals(plate.size(), Vec3::UnitZ());
  const KdTree tree(plate);
  // The scan: the plate 20 degrees off the nominal pose about z (a part placed a little askew).
  Transform placed = Transform::Identity();
  placed.linear() = Eigen::AngleAxisd(20.0 * kDeg, Vec3::UnitZ()).toRotationMatrix();
  placed.translation() = Vec3(5, -3, 2);
  std::vector<Vec3> scan;
  for (const Vec3& p : plate) scan.push_back(placed * p);
  const Transform right = placed.inverse();  // 20 degrees from identity
  Transform turned = Transform::Identity();  // the plate turned end for end onto itself
  turned.linear() = Eigen::AngleAxisd(std::numbers::pi, Vec3::UnitZ()).toRotationMatrix();
  turned.translation() = Vec3(120, 60, 0);
  IcpSettings icp;
  icp.max_iterations = 5;
  for (const auto& starts : {std::vector<Transform>{turned * right, right},
                             std::vector<Transform>{right, turned * right}}) {
    auto choice = choose_orientation(scan, tree, normals, starts, {}, icp, 1);
    ASSERT_TRUE(choice) << choice.message();
    EXPECT_TRUE(choice->symmetric_model);
    EXPECT_FALSE(choice->ambiguous);
    const Transform& best = choice->candidates[choice->best].T_cad_scan;
    EXPECT_LT(rotation_error_deg(best, right), 0.01);
    EXPECT_FALSE(choice->candidates[choice->best].equivalent);
    EXPECT_TRUE(choice->candidates[1 - choice->best].equivalent);
  }
}

TEST(Orientation, ErrorsAndTinyInputs) {
  const KdTree tree(std::vector<Vec3>{Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)});
  EXPECT_FALSE(choose_orientation({Vec3(0, 0, 0)}, tree, {}, {}, {}, {}));
  EXPECT_FALSE(choose_orientation({}, tree, {}, {Transform::Identity()}, {}, {}));
  auto one = choose_orientation({Vec3(0.1, 0.1, 0)}, tree, {}, {Transform::Identity()}, {},
                                {.method = IcpMethod::kPointToPoint});
  ASSERT_TRUE(one) << one.message();
  EXPECT_EQ(one->best, 0u);
  EXPECT_FALSE(one->ambiguous);
  EXPECT_NEAR(model_sample_spacing(tree), 1.0, 1e-12);
}

// Production parts laser-scanned from one side (sigma 0.02 mm) under poses near a half turn
// about each axis: the right orientation every time, and not called ambiguous.
class ProductionOrientation : public ::testing::TestWithParam<std::string> {};

TEST_P(ProductionOrientation, FoundFromEveryHalfTurn) {
  const auto& loaded = parts::testing::loaded_part(GetParam());
  const PartModel& m = loaded.model;
  const std::vector<double> springback(m.segmentation.bends.size(), 0.0);
  auto part = parts::make_produced_part(m, loaded.shape, springback);
  ASSERT_TRUE(part) << part.message();
  const KdTree tree(m.samples.points);
  std::mt19937 rng(163);
  for (int axis = 0; axis < 3; ++axis) {
    parts::LaserScanSettings st;
    st.point_count = 15000;
    st.noise_sigma_mm = 0.02;
    st.T_scan_part = near_half_turn(rng, axis);
    st.seed = static_cast<std::uint64_t>(10 + axis);
    const auto scan = parts::laser_scan(*part, st);
    ASSERT_TRUE(scan) << scan.message();
    auto fit = global_fit(scan->cloud.points, tree, m.samples.normals, quick_settings());
    ASSERT_TRUE(fit) << fit.message();
    // The right orientation (distinct ones are 5 degrees or more apart); how close the final ICP
    // gets on a one-sided scan of a sheet is the boundary work's business.
    EXPECT_LT(rotation_error_deg(fit->T_cad_scan, st.T_scan_part.inverse()), 1.0)
        << GetParam() << " axis " << axis << " ratio " << fit->orientation.ambiguity;
    EXPECT_FALSE(fit->ambiguous) << GetParam() << " axis " << axis;
  }
}

// Not among them yet (docs/method.md, Global fit, what is left): the front panel, whose scan (one
// skin of the sheet) can settle on the model's other skin 1.1 degrees off, no finalist starting
// in the right basin; the side panel, whose two orientations' errors come out within 3 % of each
// other (reported ambiguous, the wrong one picked).
INSTANTIATE_TEST_SUITE_P(Openamr, ProductionOrientation,
                         ::testing::Values("openamr-MMP.03.00.00.003_Motor_bracket.step",
                                           "openamr-MMP.01.00.00.002_Cover_flange.step"),
                         [](const ::testing::TestParamInfo<std::string>& p) {
                           return std::string(p.index == 0 ? "MotorBracket" : "CoverFlange");
                         });

}  // namespace
}  // namespace springscan::analysis
