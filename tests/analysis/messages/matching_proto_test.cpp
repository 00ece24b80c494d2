// Proto conversions of the matching, compensation and verdict stages.
#include "analysis/messages/matching_proto.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "analysis/messages/verdict_proto.hpp"

namespace springscan::analysis {
namespace {

TEST(MatchingProto, EmptyMessagesKeepTheDefaults) {
  const auto field = from_proto(v1::DeformationFieldSettings{});
  const auto comp = from_proto(v1::CompensationSettings{});
  const auto verdict = from_proto(v1::VerdictSettings{});
  ASSERT_TRUE(field.ok() && comp.ok() && verdict.ok());
  EXPECT_EQ(field->method, DeformationFieldSettings{}.method);
  EXPECT_EQ(field->matching.candidate_neighbors, PointMatchingSettings{}.candidate_neighbors);
  EXPECT_EQ(comp->scale, CompensationSettings{}.scale);
  EXPECT_EQ(verdict->tolerance_mm, VerdictSettings{}.tolerance_mm);
}

TEST(MatchingProto, OverridesRoundTrip) {
  DeformationFieldSettings f;
  f.method = CorrespondenceMethod::kNearestNeighbor;
  f.matching.candidate_neighbors = 7;
  f.matching.dense_limit = 300;
  v1::DeformationFieldSettings fm;
  to_proto(f, &fm);
  const auto f2 = from_proto(fm);
  ASSERT_TRUE(f2.ok());
  EXPECT_EQ(f2->method, f.method);
  EXPECT_EQ(f2->matching.candidate_neighbors, 7);
  EXPECT_EQ(f2->matching.dense_limit, 300);

  const VerdictSettings v{.tolerance_mm = 0.3,
                          .angle_tolerance_deg = 0.5,
                          .deviation_statistic = DeviationStatistic::kMax,
                          .min_coverage = 0.8,
                          .max_fit_rms_mm = 0.4};
  v1::VerdictSettings vm;
  to_proto(v, &vm);
  const auto v2 = from_proto(vm);
  ASSERT_TRUE(v2.ok());
  EXPECT_EQ(v2->deviation_statistic, DeviationStatistic::kMax);
  EXPECT_EQ(v2->tolerance_mm, 0.3);
  EXPECT_EQ(v2->min_coverage, 0.8);

  v1::CompensationSettings cm;
  to_proto(CompensationSettings{.scale = 0.8, .max_magnitude_mm = 2.0}, &cm);
  const auto c2 = from_proto(cm);
  ASSERT_TRUE(c2.ok());
  EXPECT_EQ(c2->scale, 0.8);
  EXPECT_EQ(c2->max_magnitude_mm, 2.0);
}

TEST(MatchingProto, BadValuesNameTheField) {
  v1::DeformationFieldSettings fm;
  fm.set_candidate_neighbors(0);
  const auto f = from_proto(fm);
  ASSERT_FALSE(f.ok());
  EXPECT_NE(f.message().find("deformation_field.candidate_neighbors"), std::string::npos);
  v1::CompensationSettings cm;
  cm.set_max_magnitude_mm(-1.0);
  EXPECT_NE(from_proto(cm).message().find("compensation.max_magnitude_mm"), std::string::npos);
  v1::VerdictSettings vm;
  vm.set_min_coverage(1.5);
  EXPECT_NE(from_proto(vm).message().find("verdict.min_coverage = 1.5"), std::string::npos);
}

TEST(MatchingProto, FieldAndCompensationGoIntoTheReport) {
  DeformationField field;
  field.method = CorrespondenceMethod::kMinCostMatching;
  DeformationVector v;
  v.model_index = 3;
  v.scan_index = 5;
  v.model = Vec3(1, 2, 3);
  v.scan = Vec3(1, 2, 4);
  v.squared_distance_mm2 = 1.0;
  field.vectors.push_back(v);
  field.model_points = 2;
  field.coverage = 0.5;
  field.optimality_certified = true;
  v1::InspectionReport report;
  to_proto(field, report.mutable_deformation_field());
  const auto& m = report.deformation_field();
  EXPECT_EQ(m.method(), "min_cost_matching");
  ASSERT_EQ(m.vectors_size(), 1);
  EXPECT_EQ(m.vectors(0).scan_index(), 5);
  EXPECT_EQ(m.vectors(0).scan().z(), 4.0);
  EXPECT_TRUE(m.optimality_certified());

  Compensation comp;
  comp.vectors.push_back({Vec3(1, 0, 0), Vec3(0, 0, -1), Vec3(0, 0, 1), 3, true, false});
  comp.vectors.push_back({Vec3(9, 0, 0), Vec3::Zero(), Vec3::Zero(), 0, false, false});
  append_to_report(comp, &report);
  ASSERT_EQ(report.compensation_size(), 1);
  EXPECT_EQ(report.compensation(0).vector().z(), -1.0);
}

// springscan compensate reads the field back from report.pb: the vectors come back as written.
TEST(MatchingProto, FieldReadsBackFromTheReport) {
  DeformationField field;
  field.refined = true;
  field.model_points = 3;
  for (int i = 0; i < 3; ++i) {
    DeformationVector v;
    v.model_index = static_cast<std::uint32_t>(i);
    v.model = Vec3(i, 2.0 * i, -1.0);
    v.scan = v.model + Vec3(0.1, -0.2, 0.05 * i);
    field.vectors.push_back(v);
  }
  v1::DeformationField message;
  to_proto(field, &message);
  const auto back = from_proto(message);
  ASSERT_TRUE(back) << back.message();
  EXPECT_TRUE(back->refined);
  ASSERT_EQ(back->vectors.size(), 3u);
  for (std::size_t i = 0; i < 3; ++i) {
    EXPECT_EQ(back->vectors[i].model_index, i);
    EXPECT_EQ(back->vectors[i].model, field.vectors[i].model);
    EXPECT_EQ(back->vectors[i].displacement(), field.vectors[i].displacement());
  }
  message.mutable_vectors(1)->mutable_scan()->set_x(std::nan(""));
  const auto bad = from_proto(message);
  ASSERT_FALSE(bad);
  EXPECT_TRUE(bad.error().is_corruption());
  EXPECT_NE(bad.message().find("vectors[1]"), std::string::npos);
}

}  // namespace
}  // namespace springscan::analysis
