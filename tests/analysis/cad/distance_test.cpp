#include "analysis/cad/distance.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

#include "analysis/cad/sampling.hpp"
#include "analysis/core/kdtree.hpp"
#include "simulators/parts/cad_profile.hpp"
#include "tests/analysis/cad_test_util.hpp"

namespace springscan::analysis {
using namespace springscan::parts;  // test and demo parts (simulators/parts)
namespace {

using testing::shared_cad;
using testing::TempDir;

// L profile solid: reference side z = 0 for 0 <= x <= 40 (the solid lies below it, -2 <= z <= 0),
// then a bend of inner radius 3 about the axis x = 40, z = 3 (outer radius 5), then the upright
// flange x = 43..45 up to z = 33; width 60 along y. Outward normals: +z on the top of the first
// flange, towards the axis on the inner bend face.
ProfileSpec thick_l() {
  ProfileSpec spec = l_profile(40, 30, 90, 3);
  spec.thickness_mm = 2.0;
  return spec;
}

class CadDistanceOnProfile : public ::testing::TestWithParam<const char*> {
 protected:
  void SetUp() override {
    const std::string format = GetParam();
    if (format == "built") {
      auto shape = make_profile_shape(thick_l());
      ASSERT_TRUE(shape) << shape.message();
      shape_ = *shape;
    } else {
      ASSERT_TRUE(write_profile_cad(thick_l(), dir_.file("l." + format)));
      auto shape = load_cad(dir_.file("l." + format));
      ASSERT_TRUE(shape) << shape.message();
      shape_ = *shape;
    }
    distance_ = make_cad_distance(shape_);
    ASSERT_NE(distance_, nullptr);
  }
  TempDir dir_;
  CadShape shape_;
  std::shared_ptr<const SurfaceDistance> distance_;
};

TEST_P(CadDistanceOnProfile, PlaneIsExactAndSigned) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> x(1, 38), y(10, 50), h(-0.9, 2.5);
  for (int i = 0; i < 2000; ++i) {
    const Vec3 q(x(rng), y(rng), h(rng));
    const SurfaceHit hit = distance_->closest(q);
    EXPECT_NEAR(hit.signed_distance_mm, q.z(), 1e-6) << q.transpose();
    EXPECT_NEAR((hit.foot - Vec3(q.x(), q.y(), 0)).norm(), 0.0, 1e-6);
    EXPECT_NEAR(hit.normal.z(), 1.0, 1e-9);
    EXPECT_GE(hit.face_id, 0);
  }
}

TEST_P(CadDistanceOnProfile, CylinderIsExactAndSigned) {
  const Eigen::Vector2d axis(40, 3);
  std::mt19937 rng(12);
  std::uniform_real_distribution<double> phi(0.02, std::numbers::pi / 2 - 0.02), y(10, 50),
      rho(0.5, 7.5);
  for (int i = 0; i < 2000; ++i) {
    // Polar angle measured from -z (the bend starts at the bottom of the axis, turning to +x).
    const double a = phi(rng), r = rho(rng);
    const Vec3 q(axis.x() + r * std::sin(a), y(rng), axis.y() - r * std::cos(a));
    // Inner face (radius 3): outward = towards the axis; outer face (radius 5): away from it.
    const double expected = r < 4.0 ? 3.0 - r : r - 5.0;
    const SurfaceHit hit = distance_->closest(q);
    EXPECT_NEAR(hit.signed_distance_mm, expected, 1e-6) << "r " << r << " at " << q.transpose();
    const double foot_r = std::hypot(hit.foot.x() - axis.x(), hit.foot.z() - axis.y());
    EXPECT_NEAR(foot_r, r < 4.0 ? 3.0 : 5.0, 1e-6);
    EXPECT_NEAR(std::abs(hit.signed_distance_mm), (q - hit.foot).norm(), 1e-9);
  }
}

// Beyond the free end of the first flange (x < 0) the closest points lie on the end face.
TEST_P(CadDistanceOnProfile, EndFaceAndCorner) {
  const SurfaceHit end = distance_->closest(Vec3(-1.5, 30, -1));
  EXPECT_NEAR(end.signed_distance_mm, 1.5, 1e-6);
  // Past the corner (x = 0, z = 0, y = 30) diagonally: the edge itself.
  const SurfaceHit corner = distance_->closest(Vec3(-1, 30, 1));
  EXPECT_NEAR(corner.signed_distance_mm, std::sqrt(2.0), 1e-6);
  EXPECT_NEAR((corner.foot - Vec3(0, 30, 0)).norm(), 0.0, 1e-6);
}

INSTANTIATE_TEST_SUITE_P(Formats, CadDistanceOnProfile, ::testing::Values("built", "step", "igs"));

// Oracle on a real part with fillets and holes: the exact distance is never larger than the
// distance to any point of the surface (dense samples lie exactly on it), and not much smaller
// than the nearest sample; on/off the surface along the outward normal gives the sign.
TEST(CadDistance, AgreesWithDenseSamplesOnARealPart) {
  const auto shape = load_cad(shared_cad("nema-17-bracket.step"));
  ASSERT_TRUE(shape) << shape.message();
  const auto samples = sample_cad(*shape, {.sample_count = 40000, .seed = 3});
  ASSERT_TRUE(samples);
  const KdTree tree(samples->points);
  const auto distance = make_cad_distance(*shape);
  std::mt19937 rng(5);
  const Vec3 lo = shape->report().bbox_min, hi = shape->report().bbox_max;
  std::uniform_real_distribution<double> u(0, 1);
  std::vector<Vec3> queries;
  for (int i = 0; i < 1500; ++i)
    queries.push_back(lo + (hi - lo).cwiseProduct(Vec3(u(rng), u(rng), u(rng))) * 1.1 -
                      0.05 * (hi - lo));
  const auto hits = closest_all(*distance, queries, 2);
  for (std::size_t i = 0; i < queries.size(); ++i) {
    const double sample_distance = std::sqrt(tree.nearest(queries[i])->squared_distance);
    const double d = std::abs(hits[i].signed_distance_mm);
    EXPECT_LE(d, sample_distance + 1e-7) << queries[i].transpose();
    EXPECT_GE(d, sample_distance - 0.5) << queries[i].transpose();  // sample spacing ~0.4 mm
    EXPECT_NEAR(d, (queries[i] - hits[i].foot).norm(), 1e-9);
  }
  // Sign: 0.05 mm out along the outward normal is +, in is - (the sheet is 3 mm thick).
  int positive = 0, negative = 0;
  for (std::size_t i = 0; i < samples->size(); i += 40) {
    const Vec3& p = samples->points[i];
    const Vec3& n = samples->normals[i];
    const SurfaceHit out = distance->closest(p + 0.05 * n);
    const SurfaceHit in = distance->closest(p - 0.05 * n);
    positive += out.signed_distance_mm > 0 && out.signed_distance_mm <= 0.05 + 1e-9;
    negative += in.signed_distance_mm < 0 && in.signed_distance_mm >= -0.05 - 1e-9;
    EXPECT_NEAR(distance->closest(p).signed_distance_mm, 0.0, 1e-7);
  }
  // Points near concave edges may find another face closer: allow a few.
  EXPECT_GT(positive, 980);
  EXPECT_GT(negative, 980);
}

// The deviation stage's coherent queries: each told the distance to the previous query's foot
// (a point of the surface). Near the surface in sample order, and at random through the box:
// the same answer as without the bound.
TEST(CadDistance, ClosestWithinThePreviousFootIsClosest) {
  const auto shape = load_cad(shared_cad("nema-17-bracket.step"));
  ASSERT_TRUE(shape) << shape.message();
  const auto samples = sample_cad(*shape, {.sample_count = 20000, .seed = 4});
  ASSERT_TRUE(samples);
  const auto distance = make_cad_distance(*shape);
  std::mt19937 rng(6);
  std::normal_distribution<double> noise(0.0, 0.3);
  std::vector<Vec3> queries;
  for (std::size_t i = 0; i < samples->size(); i += 4)
    queries.push_back(samples->points[i] + Vec3(noise(rng), noise(rng), noise(rng)));
  const Vec3 lo = shape->report().bbox_min, hi = shape->report().bbox_max;
  std::uniform_real_distribution<double> u(-0.1, 1.1);
  for (int i = 0; i < 1000; ++i)
    queries.push_back(lo + (hi - lo).cwiseProduct(Vec3(u(rng), u(rng), u(rng))));
  Vec3 previous = distance->closest(queries[0]).foot;
  for (std::size_t i = 1; i < queries.size(); ++i) {
    const SurfaceHit plain = distance->closest(queries[i]);
    const SurfaceHit bounded = distance->closest_within(queries[i], (queries[i] - previous).norm());
    ASSERT_EQ(bounded.signed_distance_mm, plain.signed_distance_mm) << i;
    EXPECT_EQ(bounded.face_id, plain.face_id) << i;
    previous = plain.foot;
  }
}

TEST(CadDistance, ParallelEqualsSerialAndEmpty) {
  const auto shape = make_profile_shape(hat_profile(20, 30, 40, 90, 4));
  ASSERT_TRUE(shape);
  const auto distance = make_cad_distance(*shape);
  std::mt19937 rng(9);
  std::uniform_real_distribution<double> u(-10, 120);
  std::vector<Vec3> queries(3000);
  for (auto& q : queries) q = Vec3(u(rng), u(rng) * 0.5, u(rng) * 0.4);
  const auto serial = closest_all(*distance, queries, 1);
  const auto parallel = closest_all(*distance, queries, 2);
  for (std::size_t i = 0; i < queries.size(); ++i) {
    EXPECT_EQ(serial[i].signed_distance_mm, parallel[i].signed_distance_mm);
    EXPECT_EQ(serial[i].face_id, parallel[i].face_id);
  }
  EXPECT_TRUE(closest_all(*distance, {}, 2).empty());
  EXPECT_EQ(make_cad_distance(CadShape{}), nullptr);
}

}  // namespace
}  // namespace springscan::analysis
