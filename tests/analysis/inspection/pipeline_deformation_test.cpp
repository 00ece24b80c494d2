// run_inspection fills the deformation field, the compensation vectors and the verdict
// (stages 8-9).
#include <gtest/gtest.h>

#include "analysis/cad/point_model.hpp"
#include "analysis/inspection/pipeline.hpp"
#include "tests/analysis/synthetic.hpp"

namespace springscan::analysis {
namespace {

struct Scenario {
  PartModel model;
  PointCloud scan;
};

// The bumpy part as model and an independent noisy scan of it, moved rigidly: no form error.
Scenario make_setup(unsigned seed) {
  Scenario s;
  auto model = part_model_from_points(testing::bumpy_surface(20000, seed));
  EXPECT_TRUE(model);
  s.model = std::move(model->model);
  PointCloud scan = testing::bumpy_surface(30000, seed + 1);
  scan.normals.clear();
  testing::add_noise(scan.points, 0.01, seed + 2);
  std::mt19937 rng(seed + 3);
  const Transform T_scan_cad = testing::random_motion(rng, 300.0);
  for (auto& p : scan.points) p = T_scan_cad * p;
  s.scan = std::move(scan);
  return s;
}

TEST(PipelineDeformation, FieldCompensationAndVerdictAreFilled) {
  const Scenario s = make_setup(71);
  const auto outcome = run_inspection(s.model, s.scan);
  ASSERT_TRUE(outcome) << outcome.message();
  const v1::InspectionReport& r = outcome->report;
  const v1::DeformationField& field = r.deformation_field();
  EXPECT_EQ(field.method(), "min_cost_matching");
  EXPECT_EQ(field.model_points(), r.reduction().model_points_out());
  EXPECT_EQ(field.scan_points(), r.reduction().scan_points_out());
  EXPECT_TRUE(field.optimality_certified());
  EXPECT_GT(field.coverage(), field.nearest_neighbor_coverage());
  EXPECT_GE(field.coverage(), 0.9);
  ASSERT_GT(field.vectors_size(), 10);
  // Same surface, registered: the k-center points of model and scan lie within about one
  // covering radius of each other, and the compensation is the negated smoothed field.
  for (const auto& v : field.vectors()) EXPECT_LT(std::sqrt(v.squared_distance()), 25.0);
  EXPECT_GT(r.compensation_size(), 0);
  EXPECT_LE(r.compensation_size(), field.model_points());
  EXPECT_GT(r.timings_ms().deformation(), 0.0);
  EXPECT_EQ(r.verdict().pass(), r.verdict().reasons_size() == 0);
  EXPECT_EQ(r.settings().verdict().tolerance_mm(), r.settings().deviation().tolerance_mm());
}

TEST(PipelineDeformation, SettingsReachTheStages) {
  const Scenario s = make_setup(81);
  v1::AnalysisSettings settings;
  settings.mutable_deformation_field()->set_method(v1::DeformationFieldSettings::NEAREST_NEIGHBOR);
  settings.mutable_verdict()->set_tolerance_mm(1e-4);  // nothing real is this good
  const auto outcome = run_inspection(s.model, s.scan, settings);
  ASSERT_TRUE(outcome) << outcome.message();
  const v1::InspectionReport& r = outcome->report;
  EXPECT_EQ(r.deformation_field().method(), "nearest_neighbor");
  EXPECT_DOUBLE_EQ(r.deformation_field().coverage(),
                   r.deformation_field().nearest_neighbor_coverage());
  EXPECT_FALSE(r.verdict().pass());
  ASSERT_GT(r.verdict().reasons_size(), 0);
  EXPECT_NE(r.verdict().reasons(0).find("|deviation|"), std::string::npos);

  v1::AnalysisSettings bad;
  bad.mutable_compensation()->set_max_magnitude_mm(-2.0);
  const auto refused = run_inspection(s.model, s.scan, bad);
  ASSERT_FALSE(refused);
  EXPECT_NE(refused.message().find("compensation.max_magnitude_mm"), std::string::npos);
}

}  // namespace
}  // namespace springscan::analysis
