#include "analysis/messages/springback_proto.hpp"

#include <gtest/gtest.h>

#include <algorithm>

#include "analysis/messages/verdict_proto.hpp"
#include "simulators/parts/shaped_profile.hpp"
#include "simulators/parts/sheet_part.hpp"

namespace springscan::analysis {
using namespace springscan::parts;  // test and demo parts (simulators/parts)
namespace {

TEST(SpringbackProto, ReportHoldsTheBendTableAndSegments) {
  const ProfileSpec spec = z_profile(30, 40, 80, 3);
  const auto model = profile_part_model(spec, {.sample_count = 10000});
  ASSERT_TRUE(model.ok());
  ScanSimulationSettings st;
  st.point_count = 20000;
  const auto scan = simulate_scan(spec, {1.0, 0.2}, st);
  ASSERT_TRUE(scan.ok());
  const auto result = measure_springback(*model, *scan);
  ASSERT_TRUE(result.ok());
  v1::InspectionReport report;
  fill_springback_report(*result, report);
  // The per-bend pass is the verdict's, copied into the report (verdict_proto.hpp).
  EXPECT_FALSE(report.bends(1).pass());
  to_proto(decide_verdict({.bends = result->bends}, {.angle_tolerance_deg = 0.5}), &report);
  ASSERT_EQ(report.segments_size(), 3);
  ASSERT_EQ(report.bends_size(), 2);
  EXPECT_EQ(report.segments(1).kind(), "flange");
  EXPECT_EQ(report.segments(1).cad_faces(0), 2);
  EXPECT_EQ(report.segments(1).local_fit().transform_size(), 16);
  EXPECT_EQ(report.segments(1).local_fit().transform(15), 1.0);
  EXPECT_GT(report.segments(1).points(), 1000);
  const v1::Bend& b0 = report.bends(0);
  EXPECT_NEAR(b0.springback_deg(), 1.0, 0.05);
  EXPECT_NEAR(b0.measured_angle_deg(), 79.0, 0.05);
  EXPECT_DOUBLE_EQ(b0.nominal_angle_deg(), 80.0);
  EXPECT_FALSE(b0.pass());  // 1 deg of springback against 0.5 deg tolerance
  EXPECT_TRUE(report.bends(1).pass());
  EXPECT_DOUBLE_EQ(b0.angle_tolerance_deg(), 0.5);
  EXPECT_TRUE(b0.measured());
  EXPECT_EQ(b0.segment_a(), 0);
  EXPECT_EQ(b0.segment_b(), 1);
  EXPECT_EQ(b0.cad_faces(0), 1);
  EXPECT_NEAR(std::abs(b0.axis_direction().y()), 1.0, 1e-12);
}

// The shape figures: stations, radius, end tangents, and per flange flatness, curl, twist;
// curl absent where the flange is flat.
TEST(SpringbackProto, ReportHoldsTheShapeFigures) {
  const ProfileSpec spec = u_profile(30, 40, 90, 3);
  ProfileShape shape;
  shape.springback_deg = {1.0, 0.5};
  shape.curl_radius_mm = {200, 0, 0};
  const auto model = profile_part_model(spec, {.sample_count = 10000});
  ASSERT_TRUE(model.ok());
  const auto scan = simulate_shaped_scan(spec, shape, {.point_count = 30000});
  ASSERT_TRUE(scan.ok());
  const auto result = measure_springback(*model, *scan);
  ASSERT_TRUE(result.ok());
  v1::InspectionReport report;
  fill_springback_report(*result, report);
  ASSERT_EQ(report.bends_size(), 2);
  const v1::Bend& b0 = report.bends(0);
  EXPECT_TRUE(b0.end_tangents());
  EXPECT_FALSE(report.bends(1).end_tangents());
  EXPECT_EQ(b0.angle_along_bend_size(), 3);  // 60 mm wide: the minimum of 3 stations
  EXPECT_EQ(b0.angle_along_bend(1).angle_deg(), result->bends[0].stations[1].angle_deg);
  EXPECT_NEAR(b0.angle_spread_deg(), b0.angle_max_deg() - b0.angle_min_deg(), 1e-12);
  ASSERT_TRUE(b0.has_measured_radius_mm());
  EXPECT_NEAR(b0.measured_radius_mm(), 3.0, 0.1);
  EXPECT_NE(b0.plane_angle_deg(), b0.measured_angle_deg());
  ASSERT_EQ(report.segments_size(), 3);
  EXPECT_TRUE(report.segments(0).shape_measured());
  ASSERT_TRUE(report.segments(0).has_curl_radius_mm());
  EXPECT_NEAR(report.segments(0).curl_radius_mm(), 200.0, 6.0);
  EXPECT_FALSE(report.segments(1).has_curl_radius_mm());
  EXPECT_TRUE(report.segments(1).has_twist_deg_per_100mm());
  EXPECT_NEAR(report.segments(1).flatness_rms_mm(), 0.02, 0.005);
  EXPECT_GT(report.segments(0).flatness_mm(), 0.3);  // 30 mm curled to 200 mm bows 0.56 mm
  // The end flanges' free edges (the exact profile distance gives the CAD edge); the web has none.
  ASSERT_TRUE(report.segments(2).has_edge_deviation_mm());
  EXPECT_EQ(report.segments(2).edge_deviation_mm().strips(), 3);
  // The scan is in the part's frame: the edge moved as the sections say (the springback of
  // both bends swings the last flange along itself).
  const auto nominal_end = profile_path(spec).back();
  const auto produced = shaped_section(spec, shape, 30.0);
  ASSERT_TRUE(produced.ok());
  const Eigen::Vector2d out = (nominal_end.end - nominal_end.start).normalized();
  EXPECT_NEAR(report.segments(2).edge_deviation_mm().in_plane_mean(),
              (produced->back().end - nominal_end.end).dot(out), 0.05);
  EXPECT_FALSE(report.segments(1).has_edge_deviation_mm());
  // Each edge move's U (the uncertainty stage's) reaches the report, the free edge's in both.
  SpringbackResult with_u = *result;
  ASSERT_FALSE(with_u.flanges[2].trim_edges.empty());
  for (EdgeDeviation& e : with_u.flanges[2].trim_edges)
    e.in_plane_uncertainty_mm = 0.3, e.across_uncertainty_mm = 0.04, e.uncertainty_mm = 0.3;
  v1::InspectionReport report_u;
  fill_springback_report(with_u, report_u);
  EXPECT_EQ(report_u.segments(2).edge_deviation_mm().in_plane_uncertainty_mm(), 0.3);
  EXPECT_EQ(report_u.segments(2).edge_deviation_mm().across_uncertainty_mm(), 0.04);
  EXPECT_EQ(report_u.segments(2).trim_edges(0).across_uncertainty_mm(), 0.04);
  EXPECT_EQ(report_u.segments(2).trim_edges(0).uncertainty_mm(), 0.3);
  // Every trim edge is listed, the free edge among them with the same figures.
  const auto& trim = report.segments(2).trim_edges();
  const auto free = std::find_if(trim.begin(), trim.end(),
                                 [](const v1::EdgeDeviation& e) { return e.kind() == "free"; });
  ASSERT_NE(free, trim.end());
  EXPECT_EQ(free->in_plane_mean(), report.segments(2).edge_deviation_mm().in_plane_mean());
  EXPECT_NEAR(free->outward().x() * out.x() + free->outward().z() * out.y(), 1.0, 1e-3);
  for (int s = 0; s < 3; ++s)
    for (const v1::EdgeDeviation& e : report.segments(s).trim_edges()) {
      EXPECT_TRUE(e.kind() == "free" || e.kind() == "side") << e.kind();
      EXPECT_EQ(e.cad_edge_size(), e.strips());
      EXPECT_GT(e.length_mm(), 0.0);
    }
  EXPECT_EQ(
      std::count_if(report.segments(1).trim_edges().begin(), report.segments(1).trim_edges().end(),
                    [](const v1::EdgeDeviation& e) { return e.kind() == "free"; }),
      0);
}

}  // namespace
}  // namespace springscan::analysis
