#include "analysis/inspection/pipeline.hpp"

#include <gtest/gtest.h>

#include "analysis/cad/point_model.hpp"
#include "tests/analysis/synthetic.hpp"

namespace springscan::analysis {
namespace {

constexpr double kDeg = 3.14159265358979323846 / 180.0;

Transform report_transform(const v1::GlobalFit& fit) {
  Eigen::Matrix4d M;
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) M(r, c) = fit.transform(r * 4 + c);
  Transform T = Transform::Identity();
  T.matrix() = M;
  return T;
}

struct Scenario {
  PartModel model;
  PointCloud scan;
  Transform T_cad_scan;
};

// The bumpy part as model; an independent noisy scan of it, raised 0.1 mm where x > 100 (a
// local form error), moved by a random rigid motion.
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
  s.T_cad_scan = T_scan_cad.inverse();
  return s;
}

TEST(Pipeline, FillsGlobalFitDeviationReductionAndTimings) {
  Scenario s = make_setup(51);
  s.model.source_sha256 = std::string(64, 'c');
  auto outcome = run_inspection(s.model, s.scan);
  ASSERT_TRUE(outcome) << outcome.message();
  const v1::InspectionReport& r = outcome->report;
  EXPECT_EQ(r.schema(), "springscan.report.v1");
  EXPECT_EQ(r.input().cad_sha256(), s.model.source_sha256);
  ASSERT_EQ(r.global_fit().transform_size(), 16);
  const Transform T = report_transform(r.global_fit());
  EXPECT_LT(testing::rotation_error_rad(T, s.T_cad_scan), 0.01 * kDeg);
  EXPECT_LT((T.translation() - s.T_cad_scan.translation()).norm(), 0.01);
  EXPECT_GT(r.global_fit().rms_initial(), r.global_fit().rms_final());
  EXPECT_TRUE(r.global_fit().converged()) << r.global_fit().stop_reason();
  EXPECT_EQ(r.global_fit().error_history_size(), r.global_fit().iterations() + 1);
  EXPECT_EQ(r.deviation().points(), 30000);
  EXPECT_EQ(r.deviation().reference(), "model_points");
  EXPECT_LT(r.deviation().rms(), 0.05);
  EXPECT_GT(r.reduction().model_points_out(), 10);
  EXPECT_GT(r.reduction().scan_points_out(), 10);
  EXPECT_LT(r.reduction().model_covering_radius_mm(), 10.0);
  EXPECT_GT(r.timings_ms().total(), 0.0);
  EXPECT_EQ(r.settings().normals().k_neighbors(), 10);  // the defaults in force are recorded
  EXPECT_EQ(outcome->deviation_cloud.size(), s.scan.size());
  EXPECT_EQ(outcome->deviation_cloud.scalars.size(), s.scan.size());
  EXPECT_EQ(outcome->deviation_cloud.colors.size(), s.scan.size());
}

TEST(Pipeline, SameReportForAnyThreadCount) {
  const Scenario s = make_setup(61);
  v1::AnalysisSettings one, two;
  one.set_threads(1);
  two.set_threads(2);
  auto a = run_inspection(s.model, s.scan, one);
  auto b = run_inspection(s.model, s.scan, two);
  ASSERT_TRUE(a && b);
  for (int i = 0; i < 16; ++i)
    EXPECT_EQ(a->report.global_fit().transform(i), b->report.global_fit().transform(i));
  EXPECT_EQ(a->report.deviation().rms(), b->report.deviation().rms());
  EXPECT_EQ(a->report.deviation().p95(), b->report.deviation().p95());
}

TEST(Pipeline, BadInputsAreClearErrors) {
  const Scenario s = make_setup(71);
  auto message = [&](const PartModel& model, const PointCloud& scan) {
    auto r = run_inspection(model, scan);
    return r ? std::string("(ran)") : r.message();
  };
  EXPECT_NE(message(s.model, PointCloud{}).find("scan: no points"), std::string::npos);
  PointCloud two;
  two.points = {Vec3(0, 0, 0), Vec3(1, 0, 0)};
  EXPECT_NE(message(s.model, two).find("at least 3"), std::string::npos);
  PointCloud line;
  for (int i = 0; i < 200; ++i) line.points.emplace_back(i * 0.5, 0.0, 0.0);
  EXPECT_NE(message(s.model, line).find("line"), std::string::npos);
  PointCloud nan = s.scan;
  nan.points[17].y() = NAN;
  EXPECT_NE(message(s.model, nan).find("non-finite"), std::string::npos);
  PointCloud metres = s.scan;
  for (auto& p : metres.points) p /= 1000.0;  // the scan in metres
  EXPECT_NE(message(s.model, metres).find("different units"), std::string::npos);
  v1::AnalysisSettings bad;
  bad.mutable_registration()->set_trimmed_fraction(2.0);
  auto r = run_inspection(s.model, s.scan, bad);
  ASSERT_FALSE(r);
  EXPECT_NE(r.message().find("registration.trimmed_fraction"), std::string::npos);
}

TEST(Pipeline, FlatScanRunsWithAWarning) {
  PartModel model;
  PointCloud scan;
  for (int x = 0; x < 80; ++x)
    for (int y = 0; y < 50; ++y) {
      model.samples.points.emplace_back(x, y, 0.0);
      model.samples.normals.push_back(Vec3::UnitZ());
      scan.points.emplace_back(x + 0.25, y + 0.25, 0.3);
    }
  auto r = run_inspection(model, scan);
  ASSERT_TRUE(r) << r.message();
  bool warned = false;
  for (const auto& w : r->report.warnings())
    warned |= w.find("does not constrain") != std::string::npos;
  EXPECT_TRUE(warned) << r->report.DebugString();
  EXPECT_NEAR(r->report.deviation().max(), 0.0, 1e-6);  // the constrained offset is removed
}

TEST(PointModel, EstimatesNormalsWhenMissingAndRejectsBadClouds) {
  PointCloud cloud = testing::bumpy_surface(5000, 81);
  const auto reference = cloud.normals;
  cloud.normals.clear();
  auto m = part_model_from_points(cloud);
  ASSERT_TRUE(m) << m.message();
  EXPECT_TRUE(m->normals_estimated);
  EXPECT_EQ(m->model.samples.size(), 5000u);
  EXPECT_EQ(m->model.distance, nullptr);
  for (std::size_t i = 0; i < reference.size(); ++i)
    EXPECT_GT(m->model.samples.normals[i].dot(reference[i]), 0.8);  // faces +z like the part
  EXPECT_FALSE(part_model_from_points(PointCloud{}));
  PointCloud partial = cloud;
  partial.normals.assign(10, Vec3::UnitZ());
  EXPECT_FALSE(part_model_from_points(partial));
}

}  // namespace
}  // namespace springscan::analysis
