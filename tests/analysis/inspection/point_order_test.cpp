// The same scan in another point order is the same part (issue 37): a file's order, reversed,
// shuffled (a merged multi-head scan) or in space order. The first three, in no spatial order,
// give the same report (the analysis takes such a scan in one canonical space order,
// analysis/core/spatial_order.hpp canonical_order). The demo hat is
// symmetric under a half turn, and its fitted orientation followed the sampled points, i.e. the
// order: reversed, its bends came out numbered from the other end. Truth: the demo's pose and
// springback per bend (simulators/demo_part_main.cpp).
#include <gtest/gtest.h>

#include <algorithm>
#include <numbers>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "analysis/cad/model.hpp"
#include "analysis/core/spatial_order.hpp"
#include "analysis/inspection/pipeline.hpp"
#include "simulators/parts/cad_profile.hpp"
#include "simulators/parts/demo_hat.hpp"
#include "simulators/parts/sheet_part.hpp"
#include "tests/analysis/cad_test_util.hpp"
#include "tests/analysis/under_sanitizer.hpp"

namespace springscan::analysis {
namespace {

namespace parts = springscan::parts;
constexpr double kDeg = std::numbers::pi / 180.0;
Transform report_transform(const v1::GlobalFit& fit) {
  Transform T = Transform::Identity();
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) T.matrix()(r, c) = fit.transform(r * 4 + c);
  return T;
}

PointCloud reordered(const PointCloud& scan, const std::vector<std::size_t>& order) {
  PointCloud out;
  for (std::size_t i : order) out.points.push_back(scan.points[i]);
  return out;
}

TEST(PointOrder, DemoHatKeepsItsOrientationAndBendsInEveryOrder) {
  testing::TempDir dir;
  const std::string path = dir.file("hat-profile.step");
  ASSERT_TRUE(parts::write_profile_cad(parts::demo_hat_profile(), path));
  auto model = load_part_model(path);
  ASSERT_TRUE(model) << model.message();
  parts::ScanSimulationSettings s;
  s.point_count = testing::kUnderSanitizer ? 20000 : 60000;
  s.noise_sigma_mm = 0.02;
  s.outlier_fraction = 0.005;
  s.T_scan_part = parts::demo_hat_pose();
  auto scan = parts::simulate_scan(parts::demo_hat_profile(), parts::kDemoHatSpringbackDeg, s);
  ASSERT_TRUE(scan) << scan.message();
  const std::size_t n = scan->size();
  std::vector<std::size_t> file(n);
  for (std::size_t i = 0; i < n; ++i) file[i] = i;
  std::vector<std::size_t> reversed(file.rbegin(), file.rend());
  std::vector<std::size_t> shuffled = file;
  std::mt19937_64 rng(37);
  std::shuffle(shuffled.begin(), shuffled.end(), rng);
  std::vector<std::size_t> space;
  for (std::uint32_t i : spatial_order(scan->points, 1)) space.push_back(i);
  const Transform truth = parts::demo_hat_pose().inverse();
  const std::vector<std::pair<std::string, std::vector<std::size_t>>> orders = {
      {"file", file}, {"reversed", reversed}, {"shuffled", shuffled}, {"space", space}};
  const auto apart_deg = [](const Transform& a, const Transform& b) {
    return Eigen::AngleAxisd(a.linear() * b.linear().transpose()).angle() / kDeg;
  };
  std::optional<v1::InspectionReport> first;
  PointCloud first_cloud;  // the file order's deviation cloud
  for (const auto& [name, order] : orders) {
    const PointCloud input = reordered(*scan, order);
    auto out = run_inspection(*model, input);
    ASSERT_TRUE(out) << name << ": " << out.message();
    const v1::InspectionReport& r = out->report;
    const Transform T = report_transform(r.global_fit());
    // The best fit of the sprung part lies half a degree off its pose; a half turn 180 degrees.
    EXPECT_LT(apart_deg(T, truth), 2.0) << name;
    EXPECT_FALSE(r.global_fit().ambiguous()) << name;
    ASSERT_EQ(r.bends_size(), 4) << name;
    for (int b = 0; b < 4; ++b)
      EXPECT_NEAR(r.bends(b).springback_deg(),
                  parts::kDemoHatSpringbackDeg[static_cast<std::size_t>(b)], 0.05)
          << name << " bend " << b;
    // A scan in no spatial order is taken in one canonical space order: the same report for the
    // file's order, reversed or shuffled. One in space order already is taken as it came.
    if (name == "space") continue;
    if (!first) first = r;
    EXPECT_LT(apart_deg(T, report_transform(first->global_fit())), 1e-9) << name;
    EXPECT_LT((T.translation() - report_transform(first->global_fit()).translation()).norm(), 1e-9)
        << name;
    EXPECT_NEAR(r.global_fit().rms_residual(), first->global_fit().rms_residual(), 1e-9) << name;
    EXPECT_NEAR(r.deviation().p95(), first->deviation().p95(), 1e-9) << name;
    for (int b = 0; b < 4; ++b)
      EXPECT_NEAR(r.bends(b).springback_deg(), first->bends(b).springback_deg(), 1e-6)
          << name << " bend " << b;
    // deviation.ply keeps the order the scan came in: its point i is the file's point order[i].
    ASSERT_EQ(out->deviation_cloud.size(), input.size());
    if (first_cloud.empty()) first_cloud = out->deviation_cloud;
    for (std::size_t i = 0; i < input.size(); i += 997) {
      EXPECT_LT((out->deviation_cloud.points[i] - first_cloud.points[order[i]]).norm(), 1e-9)
          << name << " point " << i;
      EXPECT_NEAR(out->deviation_cloud.scalars[i], first_cloud.scalars[order[i]], 1e-9)
          << name << " point " << i;
    }
  }
}

}  // namespace
}  // namespace springscan::analysis
