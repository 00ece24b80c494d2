#include "analysis/registration/icp.hpp"

#include <gtest/gtest.h>

#include "tests/analysis/synthetic.hpp"

namespace springscan::analysis {
namespace {

constexpr double kDeg = 3.14159265358979323846 / 180.0;

// A small known motion: the scan is the model moved by T_scan_cad, ICP must return its inverse.
Transform small_motion() {
  Transform T = Transform::Identity();
  T.linear() = Eigen::AngleAxisd(3.0 * kDeg, Vec3(0.3, -0.5, 0.8).normalized()).toRotationMatrix();
  T.translation() = Vec3(1.5, -2.0, 0.7);
  return T;
}

class IcpMethods : public ::testing::TestWithParam<IcpMethod> {};

TEST_P(IcpMethods, NoiseFreeMotionRecoveredTo1e6) {
  const PointCloud model = testing::bumpy_surface(20000, 21);
  std::vector<Vec3> scan;
  const Transform T_scan_cad = small_motion();
  for (std::size_t i = 0; i < model.size(); i += 2) scan.push_back(T_scan_cad * model.points[i]);
  IcpSettings s;
  s.method = GetParam();
  s.max_iterations = 200;
  s.error_ratio_stop = 1.0;
  const KdTree tree(model.points);
  auto r = icp(scan, tree, model.normals, Transform::Identity(), s);
  ASSERT_TRUE(r) << r.message();
  const Transform T_true = T_scan_cad.inverse();
  EXPECT_LT(testing::rotation_error_rad(r->T_target_source, T_true), 1e-6);
  EXPECT_LT((r->T_target_source.translation() - T_true.translation()).norm(), 1e-6);
  EXPECT_TRUE(r->converged) << r->stop_reason;
  EXPECT_EQ(r->error_history.size(), static_cast<std::size_t>(r->iterations) + 1);
  EXPECT_LT(r->error_history.back(), r->error_history.front());
}

TEST_P(IcpMethods, SameResultForAnyThreadCount) {
  const PointCloud model = testing::bumpy_surface(12000, 22);
  PointCloud scan = testing::bumpy_surface(9000, 23);
  testing::add_noise(scan.points, 0.05, 24);
  for (auto& p : scan.points) p = small_motion() * p;
  const KdTree tree(model.points);
  IcpSettings s;
  s.method = GetParam();
  s.max_iterations = 10;
  s.threads = 1;
  auto one = icp(scan.points, tree, model.normals, Transform::Identity(), s);
  s.threads = 4;
  auto four = icp(scan.points, tree, model.normals, Transform::Identity(), s);
  ASSERT_TRUE(one && four);
  EXPECT_EQ(one->T_target_source.matrix(), four->T_target_source.matrix());
  EXPECT_EQ(one->error_history, four->error_history);
}

INSTANTIATE_TEST_SUITE_P(BothMetrics, IcpMethods,
                         ::testing::Values(IcpMethod::kPointToPoint, IcpMethod::kPointToPlane));

TEST(Icp, NoiseAndOutliersWithinAHundredthOfADegreeAndMillimetre) {
  // The global fit's accuracy case: sigma = 0.02 mm, 2 % outliers; independent samples of model and
  // scan.
  const PointCloud model = testing::bumpy_surface(50000, 25);
  PointCloud scan = testing::bumpy_surface(50000, 26);
  testing::add_noise(scan.points, 0.02, 27);
  testing::add_outliers(scan.points, 0.02, 10.0, 28);
  const Transform T_scan_cad = small_motion();
  for (auto& p : scan.points) p = T_scan_cad * p;
  IcpSettings s;
  s.kernel = RobustKernel::kTukey;
  s.kernel_scale_mm = 1.0;
  s.trimmed_fraction = 0.05;
  const KdTree tree(model.points);
  auto r = icp(scan.points, tree, model.normals, Transform::Identity(), s);
  ASSERT_TRUE(r) << r.message();
  const Transform T_true = T_scan_cad.inverse();
  EXPECT_LT(testing::rotation_error_rad(r->T_target_source, T_true), 0.01 * kDeg);
  EXPECT_LT((r->T_target_source.translation() - T_true.translation()).norm(), 0.01);
  EXPECT_TRUE(r->converged) << r->stop_reason;
}

TEST(Icp, StopsOnIterationsAndReportsIt) {
  const PointCloud model = testing::bumpy_surface(3000, 29);
  std::vector<Vec3> scan;
  for (const auto& p : model.points) scan.push_back(small_motion() * p);
  IcpSettings s;
  s.method = IcpMethod::kPointToPoint;
  s.max_iterations = 2;
  auto r = icp(scan, KdTree(model.points), {}, Transform::Identity(), s);
  ASSERT_TRUE(r);
  EXPECT_EQ(r->iterations, 2);
  EXPECT_FALSE(r->converged);
  EXPECT_EQ(r->stop_reason, "iterations");
}

TEST(Icp, BadInputsAreErrorsNotCrashes) {
  const PointCloud model = testing::bumpy_surface(100, 30);
  const KdTree tree(model.points);
  EXPECT_FALSE(icp({}, tree, model.normals));
  EXPECT_FALSE(icp(model.points, KdTree({}), {}));
  EXPECT_FALSE(icp({Vec3(NAN, 0, 0)}, tree, model.normals));
  EXPECT_FALSE(icp(model.points, tree, {}));  // point-to-plane without normals
  IcpSettings bad;
  bad.trimmed_fraction = 1.0;
  EXPECT_FALSE(icp(model.points, tree, model.normals, Transform::Identity(), bad));
  // Two points: too few pairs for a point-to-plane solve, reported in the result.
  auto two = icp({Vec3(1, 1, 0), Vec3(2, 2, 0)}, tree, model.normals);
  ASSERT_TRUE(two);
  EXPECT_FALSE(two->converged);
  EXPECT_EQ(two->iterations, 0);
}

TEST(Icp, FlatPartIsFlaggedDegenerate) {
  std::vector<Vec3> plane;
  std::vector<Vec3> normals;
  for (int x = 0; x < 40; ++x)
    for (int y = 0; y < 40; ++y) {
      plane.emplace_back(x, y, 0);
      normals.push_back(Vec3::UnitZ());
    }
  std::vector<Vec3> scan;
  for (const auto& p : plane) scan.push_back(p + Vec3(0.3, 0.2, 0.5));
  auto r = icp(scan, KdTree(plane), normals);
  ASSERT_TRUE(r);
  EXPECT_TRUE(r->degenerate);
  EXPECT_NEAR(r->T_target_source.translation().z(), -0.5, 1e-9);  // the constrained direction
}

TEST(Icp, EveryRangeIsCheckedOnceNamingTheField) {
  IcpSettings s;
  EXPECT_FALSE(validate(s));
  s.max_inner_iterations = 0;
  const auto error = validate(s, "settings: registration.");
  ASSERT_TRUE(error);
  EXPECT_NE(error->message.find("settings: registration.max_inner_iterations = 0"),
            std::string::npos)
      << error->message;
  s = {};
  s.convergence_rotation_deg = -1.0;
  EXPECT_TRUE(validate(s));
}

TEST(Icp, ClientPairSearchWithInnerStepsAndRobustSigmaMatchesTheTreeSearch) {
  // The local fits' use of the engine: several Gauss-Newton steps per pair search and a
  // residual threshold instead of trimming. The same search written by a client gives the
  // same result as the built-in nearest-point search.
  const PointCloud model = testing::bumpy_surface(8000, 31);
  std::vector<Vec3> scan;
  for (std::size_t i = 0; i < model.size(); i += 3)
    scan.push_back(small_motion() * model.points[i]);
  const KdTree tree(model.points);
  IcpSettings s;
  s.max_inner_iterations = 5;
  s.trimmed_fraction = 0.0;
  s.inlier_sigma_factor = 3.0;
  s.min_inlier_threshold_mm = 0.01;
  s.kernel = RobustKernel::kNone;
  s.error_ratio_stop = 0.0;
  s.max_correspondence_distance_mm = 10.0;
  const IcpPairSearch own = [&](const std::vector<Vec3>& source, const Transform& T,
                                std::size_t begin, std::size_t end, std::vector<IcpPair>& pairs) {
    for (std::size_t i = begin; i < end; ++i) {
      const auto hit = tree.nearest(T * source[i], 10.0);
      pairs[i].valid = hit.has_value();
      if (!hit) continue;
      pairs[i] = {model.points[hit->index], model.normals[hit->index], hit->squared_distance, true};
    }
  };
  auto a = icp(scan, own, Transform::Identity(), s);
  auto b = icp(scan, tree, model.normals, Transform::Identity(), s);
  ASSERT_TRUE(a && b);
  EXPECT_EQ(a->T_target_source.matrix(), b->T_target_source.matrix());
  EXPECT_TRUE(a->converged) << a->stop_reason;
  EXPECT_EQ(a->stop, IcpStop::kIncrement);
  EXPECT_GT(a->updates, a->iterations);  // more than one step on some pair sets
  EXPECT_EQ(a->error_history.size(), static_cast<std::size_t>(a->iterations) + 1);
  EXPECT_LT(testing::rotation_error_rad(a->T_target_source, small_motion().inverse()), 1e-6);
}

}  // namespace
}  // namespace springscan::analysis
