#include "analysis/matching/field_evaluation.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include "analysis/matching/compensation.hpp"

namespace springscan::analysis {
namespace {

// A flat flange (z = 0, 100 x 40 mm, 2 mm grid) turning by 2 degrees about the y axis: a linear
// field d(p) = (R - I) p.
DeformationField turning_flange(const Eigen::Matrix3d& R) {
  DeformationField field;
  field.refined = true;
  for (int i = 0; i <= 50; ++i)
    for (int j = 0; j <= 20; ++j) {
      DeformationVector v;
      v.model = Vec3(2.0 * i, 2.0 * j, 0.0);
      v.scan = R * v.model;
      field.vectors.push_back(v);
    }
  return field;
}

TEST(FieldEvaluation, ReproducesALinearFieldAtTheFreeEdge) {
  const Eigen::Matrix3d R = Eigen::AngleAxisd(2.0 * EIGEN_PI / 180.0, Vec3::UnitY()).matrix();
  const DeformationField field = turning_flange(R);
  // Between the grid points, on the free edge (x = 100) and its corner, and just off the sheet.
  const std::vector<Vec3> points{
      {51.0, 13.0, 0.0}, {100.0, 21.0, 0.0}, {100.0, 40.0, 0.0}, {99.0, 1.0, 0.75}};
  const auto at = evaluate_field(field, points);
  EXPECT_NEAR(at.smoothing_radius_mm, 2.0, 1e-9);
  for (std::size_t k = 0; k < points.size(); ++k) {
    ASSERT_TRUE(at.covered[k]);
    const Vec3 truth = R * points[k] - points[k];
    // Off the sheet the gradient along the normal is unknown (held at 0): the normal component
    // (what a second skin needs) still agrees, the tangential one carries the flange's turn.
    const Vec3 error = at.deformation[k] - truth;
    EXPECT_LT(points[k].z() == 0.0 ? error.norm() : std::abs(error.z()), 2e-3) << "point " << k;
  }
  // The Gaussian average of compensation.hpp is biased there by the gradient (why this exists).
  const auto gaussian = compensation(field, {points[1]});
  ASSERT_TRUE(gaussian);
  EXPECT_GT((gaussian->vectors[0].deformation - (R * points[1] - points[1])).norm(), 0.03);
}

// The spread is the field's scatter about the local fit: 0 for a linear field, the noise's
// sigma for a noisy one; a free direction's component is dropped.
TEST(FieldEvaluation, SpreadIsTheNoiseAndFreeDirectionsAreDropped) {
  const Eigen::Matrix3d R = Eigen::AngleAxisd(2.0 * EIGEN_PI / 180.0, Vec3::UnitY()).matrix();
  DeformationField field = turning_flange(R);
  const std::vector<Vec3> points{{51.0, 13.0, 0.0}, {30.0, 20.0, 0.0}};
  for (const double s : evaluate_field(field, points).spread_mm) EXPECT_LT(s, 1e-3);
  // +-0.05 mm along z in a checkerboard: sigma 0.05 mm, mean 0.
  for (std::size_t i = 0; i < field.vectors.size(); ++i)
    field.vectors[i].scan.z() += (i % 2 == 0 ? 0.05 : -0.05);
  for (const double s : evaluate_field(field, points).spread_mm) EXPECT_NEAR(s, 0.05, 0.01);
  FieldEvaluationSettings free;
  free.free_directions = {Vec3::UnitX()};
  const auto at = evaluate_field(turning_flange(R), points, free);
  for (std::size_t k = 0; k < points.size(); ++k) {
    const Vec3 truth = R * points[k] - points[k];
    EXPECT_NEAR(at.deformation[k].x(), 0.0, 1e-12);
    EXPECT_NEAR(at.deformation[k].z(), truth.z(), 1e-6);
  }
}

TEST(FieldEvaluation, FarPointsAndEmptyFieldsAreNotCovered) {
  const DeformationField field = turning_flange(Eigen::Matrix3d::Identity());
  const auto at = evaluate_field(field, {Vec3(200.0, 0.0, 0.0), Vec3(50.0, 20.0, 0.0)});
  EXPECT_FALSE(at.covered[0]);
  EXPECT_TRUE(at.deformation[0].isZero());
  EXPECT_TRUE(at.covered[1]);
  const auto empty = evaluate_field(DeformationField{}, {Vec3::Zero()});
  EXPECT_FALSE(empty.covered[0]);
  EXPECT_TRUE(evaluate_field(field, {}).deformation.empty());
  // A single vector: only its own point is covered.
  DeformationField one;
  one.vectors.push_back(field.vectors[3]);
  const auto single = evaluate_field(one, {field.vectors[3].model, Vec3(0.0, 0.0, 1.0)});
  EXPECT_TRUE(single.covered[0]);
  EXPECT_FALSE(single.covered[1]);
}

}  // namespace
}  // namespace springscan::analysis
