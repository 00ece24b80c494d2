// The deformation field, and the paper's Figure 9 contrast: on a profile with a sharp bend
// whose flange was bent open, the one-to-one matching maps edge points to edge points and
// covers the model; nearest neighbour leaves the moved edge uncovered.
#include "analysis/matching/deformation_field.hpp"

#include <gtest/gtest.h>

#include <limits>
#include <random>

#include "tests/analysis/profile_sampling.hpp"

namespace springscan::analysis {
namespace {

using testing::ProfileSamples;
using testing::sample_profile;

struct BentOpenL {
  ProfileSamples model;
  ProfileSamples scan;
};

// An L profile (30 mm legs, sharp 0.5 mm bend radius, 6 mm wide) at its nominal 90 degrees,
// and the same part sprung open to 70 degrees, sampled sample-for-sample alike (the same
// count per path element), as two k-center reductions with the same w would be.
BentOpenL bent_open_l() {
  ProfileSpec nominal = l_profile(30.0, 30.0, 90.0, 0.5);
  nominal.width_mm = 6.0;
  ProfileSpec sprung = nominal;
  sprung.bend_angles_deg[0] = 70.0;
  const std::vector<int> counts{30, 2, 30};
  return {sample_profile(nominal, counts, 4), sample_profile(sprung, counts, 4)};
}

TEST(DeformationField, MatchingMapsEdgesToEdgesNearestNeighbourDoesNot) {
  const BentOpenL l = bent_open_l();
  const int tip = l.model.last_step;
  ASSERT_EQ(l.scan.last_step, tip);

  const auto matched = deformation_field(l.model.points, l.scan.points);
  ASSERT_TRUE(matched.ok()) << matched.message();
  EXPECT_DOUBLE_EQ(matched->coverage, 1.0);
  EXPECT_TRUE(matched->optimality_certified);
  int tips = 0;
  for (const auto& v : matched->vectors) {
    if (l.model.path_step[v.model_index] != tip) continue;
    ++tips;
    EXPECT_EQ(l.scan.path_step[v.scan_index], tip) << "model edge point " << v.model_index;
  }
  EXPECT_EQ(tips, 4);  // one edge point per row across the width

  DeformationFieldSettings nn;
  nn.method = CorrespondenceMethod::kNearestNeighbor;
  const auto nearest = deformation_field(l.model.points, l.scan.points, nn);
  ASSERT_TRUE(nearest.ok());
  EXPECT_LT(nearest->coverage, 0.97);
  EXPECT_DOUBLE_EQ(nearest->coverage, matched->nearest_neighbor_coverage);
  for (const auto& v : nearest->vectors) {
    EXPECT_NE(l.model.path_step[v.model_index], tip) << "the moved edge stays uncovered";
    if (l.scan.path_step[v.scan_index] == tip) {
      EXPECT_LT(l.model.path_step[v.model_index], tip - 1) << "scan edge lands inside the flange";
    }
  }
}

TEST(DeformationField, RigidShiftIsRecoveredByBothMethods) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(0.0, 50.0);
  std::vector<Vec3> model(200), scan;
  for (auto& p : model) p = Vec3(u(rng), u(rng), u(rng));
  const Vec3 shift(0.05, -0.02, 0.03);  // far below the point spacing
  for (const auto& p : model) scan.push_back(p + shift);
  for (const auto method :
       {CorrespondenceMethod::kMinCostMatching, CorrespondenceMethod::kNearestNeighbor}) {
    DeformationFieldSettings settings;
    settings.method = method;
    const auto field = deformation_field(model, scan, settings);
    ASSERT_TRUE(field.ok());
    EXPECT_DOUBLE_EQ(field->coverage, 1.0) << to_string(method);
    ASSERT_EQ(field->vectors.size(), model.size());
    for (const auto& v : field->vectors) {
      EXPECT_EQ(v.model_index, v.scan_index);
      EXPECT_NEAR((v.displacement() - shift).norm(), 0.0, 1e-12);
    }
    EXPECT_NEAR(field->total_cost_mm2, 200 * shift.squaredNorm(), 1e-9);
  }
}

TEST(DeformationField, FewerScanPointsCoverOnlyPartOfTheModel) {
  std::vector<Vec3> model, scan;
  for (int i = 0; i < 10; ++i) model.emplace_back(i, 0, 0);
  for (int i = 0; i < 6; ++i) scan.emplace_back(i, 0.1, 0);
  const auto field = deformation_field(model, scan);
  ASSERT_TRUE(field.ok());
  EXPECT_DOUBLE_EQ(field->coverage, 0.6);
  EXPECT_TRUE(field->optimality_certified);
  EXPECT_NEAR(field->total_cost_mm2, 6 * 0.01, 1e-12);
}

TEST(DeformationField, EmptyInputsAndBadPoints) {
  auto field = deformation_field({}, {});
  ASSERT_TRUE(field.ok());
  EXPECT_TRUE(field->vectors.empty());
  EXPECT_EQ(field->coverage, 0.0);
  field = deformation_field({Vec3::Zero()}, {});
  ASSERT_TRUE(field.ok());
  EXPECT_EQ(field->coverage, 0.0);
  field = deformation_field({Vec3::Zero()}, {Vec3(std::numeric_limits<double>::infinity(), 0, 0)});
  ASSERT_FALSE(field.ok());
  EXPECT_NE(field.message().find("scan point 0"), std::string::npos) << field.message();
}

}  // namespace
}  // namespace springscan::analysis
