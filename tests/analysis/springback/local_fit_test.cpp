#include "analysis/springback/local_fit.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "analysis/springback/relative_rotation.hpp"
#include "simulators/parts/sheet_part.hpp"

namespace springscan::analysis {
using namespace springscan::parts;  // test and demo parts (simulators/parts)
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

PartModel model_of(const ProfileSpec& spec, int samples = 20000) {
  auto model = profile_part_model(spec, {.sample_count = samples});
  EXPECT_TRUE(model.ok());
  return std::move(model).value();
}

PointCloud exact_scan(const ProfileSpec& spec, std::int64_t points) {
  ScanSimulationSettings st;
  st.point_count = points;
  st.noise_sigma_mm = 0.0;
  return *simulate_scan(spec, std::vector<double>(spec.bend_angles_deg.size(), 0.0), st);
}

// Turns the points at `indices` by `motion` (in place).
void move(PointCloud& scan, const std::vector<std::uint32_t>& indices, const Transform& motion) {
  for (std::uint32_t i : indices) scan.points[i] = motion * scan.points[i];
}

Vec3 centroid(const PointCloud& scan, const std::vector<std::uint32_t>& indices) {
  Vec3 c = Vec3::Zero();
  for (std::uint32_t i : indices) c += scan.points[i];
  return c / static_cast<double>(indices.size());
}

TEST(LocalFit, ReproducesThePaperFigure8Rotation) {
  // A U profile with two 90 degree bends. Subset A: flange 0, bend 0 and the first half of the
  // web; subset B: the second half of the web, bend 1 and flange 2. Each is an L, so each fit
  // determines every rotation (only sliding along the extrusion stays free).
  const ProfileSpec spec = u_profile(30, 40, 90, 4);
  const PartModel model = model_of(spec);
  PointCloud scan = exact_scan(spec, 30000);
  const auto A = points_in_box(scan, Eigen::AlignedBox3d(Vec3(-1, -1, -1), Vec3(60, 61, 20)));
  const auto B = points_in_box(scan, Eigen::AlignedBox3d(Vec3(-60, -1, 24), Vec3(60, 61, 60)));
  ASSERT_GT(A.size(), 5000u);
  ASSERT_GT(B.size(), 5000u);
  const Vec3 axis = Vec3(-0.2614, 0.1958, 0.9452).normalized();
  const double angle_deg = 8.8448;
  const Vec3 c = centroid(scan, B);
  move(scan, B,
       Eigen::Translation3d(c) * Eigen::AngleAxisd(angle_deg * kDeg, axis) *
           Eigen::Translation3d(-c));

  const LocalFitTarget target(model);
  LocalFitSettings st;
  st.correspondence = LocalFitCorrespondence::kExactSurface;
  st.max_correspondence_distance_mm = 10.0;
  const auto fit_a = local_fit(target, scan, A, st);
  const auto fit_b = local_fit(target, scan, B, st);
  ASSERT_TRUE(fit_a.ok()) << fit_a.message();
  ASSERT_TRUE(fit_b.ok()) << fit_b.message();
  EXPECT_TRUE(fit_b->converged);
  EXPECT_EQ(fit_b->determined_directions, 5);
  EXPECT_LT(fit_b->rms_mm, 1e-6);
  EXPECT_GT(fit_b->error_history.front(), 1.0);  // B started far off
  const AxisAngle r = relative_rotation(fit_a->T_model_subset, fit_b->T_model_subset);
  EXPECT_NEAR((r.axis - axis).norm(), 0.0, 1e-4);
  EXPECT_NEAR(r.angle_deg, angle_deg, 1e-3);
}

TEST(LocalFit, FlatFlangeFitsOnlyWhatItDetermines) {
  const ProfileSpec spec = l_profile(50, 40, 90, 3);
  const PartModel model = model_of(spec);
  PointCloud scan = exact_scan(spec, 20000);
  const auto flange = points_in_box(scan, Eigen::AlignedBox3d(Vec3(2, -1, -1), Vec3(45, 61, 1)));
  // In-plane motion the flange cannot reveal (2 deg about its normal, a 1.5 mm slide), then a
  // tilt and a lift it does reveal.
  const Transform in_plane =
      Eigen::Translation3d(1.5, -1.0, 0.0) * Eigen::AngleAxisd(2.0 * kDeg, Vec3::UnitZ());
  const Transform tilt =
      Eigen::Translation3d(0, 0, 0.2) * Eigen::AngleAxisd(0.5 * kDeg, Vec3::UnitX());
  move(scan, flange, tilt * in_plane);
  const LocalFitTarget target(model);
  const auto fit = local_fit(target, scan, flange);
  ASSERT_TRUE(fit.ok()) << fit.message();
  EXPECT_TRUE(fit->converged);
  EXPECT_EQ(fit->determined_directions, 3);
  EXPECT_LT(fit->rms_mm, 1e-9);
  // The fitted plane is the tilted plane exactly...
  const Vec3 fitted_normal = fit->T_model_subset.linear().transpose() * Vec3::UnitZ();
  EXPECT_NEAR((fitted_normal - tilt.linear() * Vec3::UnitZ()).norm(), 0.0, 1e-12);
  // ...and the fit added no turn about the normal: it undid the 0.5 deg tilt and nothing else.
  const AxisAngle turn = axis_angle_of(fit->T_model_subset.linear());
  EXPECT_NEAR(turn.angle_deg, 0.5, 1e-9);
  EXPECT_NEAR(std::abs(turn.axis.z()), 0.0, 1e-9);
}

TEST(LocalFit, ResultDoesNotDependOnTheThreadCount) {
  const ProfileSpec spec = l_profile(50, 40, 80, 3);
  const PartModel model = model_of(spec);
  PointCloud scan = exact_scan(spec, 20000);
  std::vector<std::uint32_t> all(scan.size());
  for (std::uint32_t i = 0; i < all.size(); ++i) all[i] = i;
  move(scan, all, Transform(Eigen::AngleAxisd(0.01, Vec3(1, 1, 0).normalized())));
  const LocalFitTarget target(model);
  LocalFitSettings one, two;
  one.threads = 1;
  two.threads = 2;
  const auto a = local_fit(target, scan, all, one);
  const auto b = local_fit(target, scan, all, two);
  ASSERT_TRUE(a.ok() && b.ok());
  EXPECT_EQ(a->T_model_subset.matrix(), b->T_model_subset.matrix());
  EXPECT_EQ(a->error_history, b->error_history);
}

TEST(LocalFit, SubsetsByFaceAndErrorsOnBadInput) {
  const ProfileSpec spec = l_profile(50, 40, 90, 3);
  const PartModel model = model_of(spec, 5000);
  const PointCloud scan = exact_scan(spec, 5000);
  const LocalFitTarget target(model);
  const auto on_bend = points_on_faces(target, scan, {1});
  ASSERT_FALSE(on_bend.empty());
  for (std::uint32_t i : on_bend) EXPECT_EQ(model.distance->closest(scan.points[i]).face_id, 1);
  EXPECT_FALSE(local_fit(target, scan, {}).ok());
  EXPECT_FALSE(local_fit(target, scan, {0, 1, 2}).ok());
  std::vector<std::uint32_t> bad(100, 0);
  bad.back() = 5000;
  const auto out_of_range = local_fit(target, scan, bad);
  ASSERT_FALSE(out_of_range.ok());
  EXPECT_NE(out_of_range.message().find("index 5000"), std::string::npos);
  PointCloud with_nan = scan;
  with_nan.points[3].x() = std::nan("");
  std::vector<std::uint32_t> first(200);
  for (std::uint32_t i = 0; i < first.size(); ++i) first[i] = i;
  const auto not_finite = local_fit(target, with_nan, first);
  ASSERT_FALSE(not_finite.ok());
  EXPECT_NE(not_finite.message().find("point 3"), std::string::npos);
  const PointCloud far_away = transformed(scan, Transform(Eigen::Translation3d(0, 0, 500)));
  std::vector<std::uint32_t> all(far_away.size());
  for (std::uint32_t i = 0; i < all.size(); ++i) all[i] = i;
  EXPECT_FALSE(local_fit(target, far_away, all).ok());
}

}  // namespace
}  // namespace springscan::analysis
