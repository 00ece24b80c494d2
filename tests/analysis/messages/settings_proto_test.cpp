#include "analysis/messages/settings_proto.hpp"

#include <google/protobuf/text_format.h>
#include <gtest/gtest.h>

#include "analysis/messages/verdict_proto.hpp"

namespace springscan::analysis {
namespace {

v1::AnalysisSettings parse(const std::string& text) {
  v1::AnalysisSettings m;
  EXPECT_TRUE(google::protobuf::TextFormat::ParseFromString(text, &m)) << text;
  return m;
}

TEST(SettingsProto, UnsetFieldsKeepTheStructDefaults) {
  const v1::AnalysisSettings m;
  auto fit = from_proto(m.registration());
  ASSERT_TRUE(fit);
  const GlobalFitSettings defaults;
  EXPECT_EQ(fit->icp.max_iterations, defaults.icp.max_iterations);
  EXPECT_EQ(fit->icp.trimmed_fraction, defaults.icp.trimmed_fraction);
  EXPECT_EQ(fit->pca_initial_alignment, defaults.pca_initial_alignment);
  auto reduction = from_proto(m.reduction());
  ASSERT_TRUE(reduction);
  EXPECT_EQ(reduction->kcenter.radius_mm, 10.0);
  EXPECT_EQ(from_proto(m.normals())->k_neighbors, 10);
  EXPECT_EQ(verdict_settings_from_proto(m)->tolerance_mm, VerdictSettings{}.tolerance_mm);
}

TEST(SettingsProto, SetFieldsOverride) {
  const auto m = parse(R"(
    normals { k_neighbors: 16 radius_mm: 2.5 }
    reduction { kcenter_radius_mm: 7 kcenter_count: 300 voxel_size_mm: 1.5 min_curvature: 0.02 }
    registration { method: POINT_TO_POINT max_iterations: 12 robust_kernel: TUKEY
                   kernel_scale_mm: 0.3 trimmed_fraction: 0.2 pca_initial_alignment: false
                   error_ratio_stop: 0.999 max_correspondence_distance_mm: 4 min_error_mm: 0.001 }
    deviation { tolerance_mm: 0.25 }
    threads: 2)");
  auto normals = from_proto(m.normals());
  auto reduction = from_proto(m.reduction());
  auto fit = from_proto(m.registration());
  auto verdict = verdict_settings_from_proto(m);
  ASSERT_TRUE(normals && reduction && fit && verdict);
  EXPECT_EQ(normals->k_neighbors, 16);
  EXPECT_EQ(normals->radius_mm, 2.5);
  EXPECT_EQ(reduction->kcenter.radius_mm, 7.0);
  EXPECT_EQ(reduction->kcenter.center_count, 300u);
  EXPECT_EQ(reduction->voxel_size_mm, 1.5);
  EXPECT_EQ(reduction->curvature.min_curvature, 0.02);
  EXPECT_EQ(fit->icp.method, IcpMethod::kPointToPoint);
  EXPECT_EQ(fit->icp.kernel, RobustKernel::kTukey);
  EXPECT_EQ(fit->icp.max_iterations, 12);
  EXPECT_EQ(fit->icp.kernel_scale_mm, 0.3);
  EXPECT_EQ(fit->icp.trimmed_fraction, 0.2);
  EXPECT_EQ(fit->icp.error_ratio_stop, 0.999);
  EXPECT_EQ(fit->icp.max_correspondence_distance_mm, 4.0);
  EXPECT_EQ(fit->icp.min_error_mm, 0.001);
  EXPECT_FALSE(fit->pca_initial_alignment);
  EXPECT_EQ(verdict->tolerance_mm, 0.25);  // deviation.tolerance_mm sets the verdict's
  EXPECT_EQ(*threads_from_proto(m), 2);
}

TEST(SettingsProto, ErrorsNameTheFieldAndValue) {
  auto expect_error = [](const Expected<GlobalFitSettings>& r, const std::string& field) {
    ASSERT_FALSE(r);
    EXPECT_NE(r.message().find(field), std::string::npos) << r.message();
  };
  expect_error(from_proto(parse("registration { trimmed_fraction: 1.5 }").registration()),
               "registration.trimmed_fraction = 1.5");
  expect_error(from_proto(parse("registration { max_iterations: -3 }").registration()),
               "registration.max_iterations = -3");
  expect_error(from_proto(parse("registration { kernel_scale_mm: 0 }").registration()),
               "registration.kernel_scale_mm");
  v1::RegistrationSettings bad_enum;
  bad_enum.set_method(static_cast<v1::RegistrationSettings::Method>(9));
  expect_error(from_proto(bad_enum), "registration.method");
  auto k = from_proto(parse("normals { k_neighbors: 100000000 }").normals());
  ASSERT_FALSE(k);
  EXPECT_NE(k.message().find("normals.k_neighbors"), std::string::npos);
  EXPECT_FALSE(from_proto(parse("reduction { kcenter_radius_mm: -1 }").reduction()));
  EXPECT_FALSE(from_proto(parse("reduction { voxel_size_mm: nan }").reduction()));
  EXPECT_NE(verdict_settings_from_proto(parse("deviation { tolerance_mm: 0 }"))
                .message()
                .find("deviation.tolerance_mm = 0"),
            std::string::npos);
  EXPECT_FALSE(threads_from_proto(parse("threads: -1")));
}

// The verdict owns the surface tolerance; deviation.tolerance_mm, its older place, sets it only
// when verdict.tolerance_mm does not, and both go through the same range check.
TEST(SettingsProto, TheSurfaceToleranceHasOneOwnerAndOneRange) {
  EXPECT_EQ(verdict_settings_from_proto(
                parse("deviation { tolerance_mm: 0.2 } verdict { tolerance_mm: 0.3 }"))
                ->tolerance_mm,
            0.3);
  for (const char* text : {"deviation { tolerance_mm: 2e6 }", "verdict { tolerance_mm: 2e6 }",
                           "verdict { tolerance_mm: nan }"}) {
    const auto v = verdict_settings_from_proto(parse(text));
    ASSERT_FALSE(v) << text;
    EXPECT_NE(v.message().find("(0 < mm <= 1e6)"), std::string::npos) << v.message();
  }
  EXPECT_NE(verdict_settings_from_proto(parse("verdict { angle_tolerance_deg: 181 }"))
                .message()
                .find("verdict.angle_tolerance_deg = 181"),
            std::string::npos);
}

TEST(SettingsProto, RoundTripOfTheSettingsInForce) {
  GlobalFitSettings fit;
  fit.icp.max_iterations = 17;
  fit.icp.kernel = RobustKernel::kNone;
  v1::RegistrationSettings m;
  to_proto(fit, &m);
  auto back = from_proto(m);
  ASSERT_TRUE(back);
  EXPECT_EQ(back->icp.max_iterations, 17);
  EXPECT_EQ(back->icp.kernel, RobustKernel::kNone);
  EXPECT_EQ(back->icp.trimmed_fraction, fit.icp.trimmed_fraction);
}

// The shape settings: stations and curl in springback, the shape limits in verdict (off,
// i.e. 0, by default; negative refused, 0 accepted).
TEST(SettingsProto, ShapeSettingsOverrideAndAreChecked) {
  const auto m = parse(R"(
    springback { station_spacing_mm: 25 min_stations: 5 min_curl_sagitta_mm: 0.05 }
    verdict { max_angle_spread_deg: 0.4 min_curl_radius_mm: 300 max_flatness_mm: 0.8
              max_edge_deviation_mm: 0.25 })");
  const auto springback = from_proto(m.springback());
  const auto verdict = verdict_settings_from_proto(m);
  ASSERT_TRUE(springback && verdict);
  EXPECT_EQ(springback->shape.station_spacing_mm, 25.0);
  EXPECT_EQ(springback->shape.min_stations, 5);
  EXPECT_EQ(springback->shape.flange.min_curl_sagitta_mm, 0.05);
  EXPECT_EQ(verdict->max_angle_spread_deg, 0.4);
  EXPECT_EQ(verdict->min_curl_radius_mm, 300.0);
  EXPECT_EQ(verdict->max_flatness_mm, 0.8);
  EXPECT_EQ(verdict->max_edge_deviation_mm, 0.25);
  const auto defaults = verdict_settings_from_proto(parse(""));
  EXPECT_EQ(defaults->max_angle_spread_deg, 0.0);
  EXPECT_EQ(defaults->min_curl_radius_mm, 0.0);
  EXPECT_EQ(defaults->max_flatness_mm, 0.0);
  EXPECT_EQ(defaults->max_edge_deviation_mm, 0.0);
  EXPECT_TRUE(verdict_settings_from_proto(parse("verdict { max_flatness_mm: 0 }")));
  EXPECT_EQ(defaults->decision_rule, DecisionRule::kGuardBand);
  EXPECT_EQ(verdict_settings_from_proto(parse("verdict { decision_rule: SIMPLE }"))->decision_rule,
            DecisionRule::kSimple);
  EXPECT_NE(verdict_settings_from_proto(parse("verdict { min_curl_radius_mm: -1 }"))
                .message()
                .find("verdict.min_curl_radius_mm = -1"),
            std::string::npos);
  EXPECT_NE(from_proto(parse("springback { station_spacing_mm: 0 }").springback())
                .message()
                .find("springback.station_spacing_mm"),
            std::string::npos);
  EXPECT_FALSE(from_proto(parse("springback { min_stations: 0 }").springback()));
  v1::SpringbackSettings out;
  to_proto(*springback, &out);
  EXPECT_EQ(out.station_spacing_mm(), 25.0);
  EXPECT_EQ(out.min_stations(), 5);
}

}  // namespace
}  // namespace springscan::analysis

namespace springscan::analysis {
namespace {

TEST(SettingsProto, MeshDecimationOverridesRangesAndRoundTrip) {
  auto defaults = from_proto(v1::ReductionSettings{});
  ASSERT_TRUE(defaults);
  EXPECT_FALSE(defaults->mesh_decimation.enabled);
  EXPECT_EQ(defaults->mesh_decimation.max_error_mm, DecimationSettings{}.max_error_mm);
  const auto m = parse(R"(reduction { mesh_decimation { enabled: true target_reduction: 0.7
                          feature_angle_deg: 30 boundary_vertex_deletion: true
                          max_error_mm: 0.02 } })");
  auto s = from_proto(m.reduction());
  ASSERT_TRUE(s) << s.message();
  EXPECT_TRUE(s->mesh_decimation.enabled);
  EXPECT_EQ(s->mesh_decimation.target_reduction, 0.7);
  EXPECT_EQ(s->mesh_decimation.feature_angle_deg, 30.0);
  EXPECT_TRUE(s->mesh_decimation.boundary_vertex_deletion);
  EXPECT_EQ(s->mesh_decimation.max_error_mm, 0.02);
  v1::ReductionSettings back;
  to_proto(*s, &back);
  auto again = from_proto(back);
  ASSERT_TRUE(again);
  EXPECT_EQ(again->mesh_decimation.max_error_mm, 0.02);
  EXPECT_TRUE(again->mesh_decimation.boundary_vertex_deletion);
  const auto bad =
      from_proto(parse("reduction { mesh_decimation { target_reduction: 1.5 } }").reduction());
  ASSERT_FALSE(bad);
  EXPECT_EQ(bad.code(), ErrorCode::kInvalidSettings);
  EXPECT_NE(bad.message().find("reduction.mesh_decimation.target_reduction = 1.5"),
            std::string::npos)
      << bad.message();
}

}  // namespace
}  // namespace springscan::analysis
