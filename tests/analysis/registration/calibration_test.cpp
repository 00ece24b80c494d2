// Head calibration (analysis/registration/calibration.hpp) on the simulator: the shipped
// artefact (simulators/parts/artefact.hpp) scanned by heads mounted with known errors
// (simulators/parts/head_scan.hpp: 0.5 degree, 2 mm, a 0.2 % encoder scale, noise sigma
// 0.02 mm, 1 % outliers) must come back within 0.01 degree and 0.01 mm, the scale within 1e-4;
// a view that leaves directions free is refused with them named.
#include "analysis/registration/calibration.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <numbers>

#include "analysis/cad/model.hpp"
#include "simulators/parts/artefact.hpp"
#include "simulators/parts/head_scan.hpp"

namespace springscan::analysis {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;
class HeadCalibrationTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    const auto path = std::filesystem::temp_directory_path() /
                      ("springscan_artefact_" + std::to_string(::getpid()) + ".step");
    auto written = parts::write_artefact_step(path.string());
    ASSERT_TRUE(written.ok()) << written.message();
    auto model = load_part_model(path.string());
    std::filesystem::remove(path);
    ASSERT_TRUE(model.ok()) << model.message();
    model_ = new PartModel(std::move(*model));
  }
  static void TearDownTestSuite() {
    delete model_;
    model_ = nullptr;
  }
  static PartModel* model_;
};
PartModel* HeadCalibrationTest::model_ = nullptr;

struct Recovery {
  double rotation_deg = 0.0;     // angle of T_fit^-1 T_true
  double displacement_mm = 0.0;  // largest |T_fit p - T_true p| over the head's points
};

Recovery recovery(const HeadCalibration& fit, const Transform& truth, double true_scale,
                  const PointCloud& raw) {
  Recovery r;
  const Eigen::AngleAxisd delta((fit.T_station_head.linear().transpose() * truth.linear()).eval());
  r.rotation_deg = std::abs(delta.angle()) / kDeg;
  for (const Vec3& p : raw.points) {
    const Vec3 fitted = fit.T_station_head * Vec3(p.x(), p.y(), fit.motion_scale * p.z());
    const Vec3 real = truth * Vec3(p.x(), p.y(), true_scale * p.z());
    r.displacement_mm = std::max(r.displacement_mm, (fitted - real).norm());
  }
  return r;
}

parts::HeadScanSettings head(const Transform& truth, double scale, std::uint64_t seed) {
  return parts::demo_head_scan(truth, scale, seed);
}

TEST_F(HeadCalibrationTest, RecoversEveryHeadsMountAndTheEncoderScale) {
  std::uint64_t seed = 1;
  for (const parts::DemoHead& c : parts::demo_heads()) {
    SCOPED_TRACE(c.name);
    const Transform& truth = c.truth;
    const double true_scale = 1.002;
    auto raw = parts::head_scan(model_->mesh, head(truth, true_scale, seed++));
    ASSERT_TRUE(raw.ok()) << raw.message();
    ASSERT_GT(raw->points.size(), 3000u);
    HeadCalibrationSettings settings;
    settings.fit_motion_scale = true;
    auto fit = calibrate_head(raw->points, *model_, settings);
    ASSERT_TRUE(fit.ok()) << fit.message();
    const Recovery r = recovery(*fit, truth, true_scale, *raw);
    std::printf(
        "head %s: %zu points, rotation error %.5f deg, displacement error %.5f mm, "
        "scale error %.2e, rms %.4f mm, p95 %.4f mm, sigma rot %.5f %.5f %.5f deg, "
        "sigma t %.5f %.5f %.5f mm, sigma k %.2e, weakest %.3f, %d rounds\n",
        c.name.c_str(), raw->points.size(), r.rotation_deg, r.displacement_mm,
        fit->motion_scale - true_scale, fit->rms_mm, fit->p95_mm, fit->rotation_sigma_deg.x(),
        fit->rotation_sigma_deg.y(), fit->rotation_sigma_deg.z(), fit->translation_sigma_mm.x(),
        fit->translation_sigma_mm.y(), fit->translation_sigma_mm.z(), fit->motion_scale_sigma,
        fit->weakest_direction_ratio, fit->scale_rounds);
    EXPECT_LT(r.rotation_deg, 0.01);
    EXPECT_LT(r.displacement_mm, 0.01);
    EXPECT_NEAR(fit->motion_scale, true_scale, 1e-4);
    // The residuals are the noise seen along the surface normal: sigma 0.02 along the ray times
    // the cosine of the incidence (1 on the flats, 0.7 on the 45-degree chamfers); the outliers
    // left out.
    EXPECT_GT(fit->rms_mm, 0.012);
    EXPECT_LT(fit->rms_mm, 0.021);
    EXPECT_LT(fit->inliers, fit->fitted_points);
    // The stated uncertainty is small and not wildly optimistic about the error made.
    EXPECT_LT(fit->rotation_sigma_deg.maxCoeff(), 0.005);
    EXPECT_LT(fit->translation_sigma_mm.maxCoeff(), 0.005);
    EXPECT_LT(r.rotation_deg, 6.0 * fit->rotation_sigma_deg.norm() + 1e-4);
  }
}

TEST_F(HeadCalibrationTest, RigidOnlyWithoutTheScale) {
  const Transform truth = parts::demo_heads()[1].truth;
  auto raw = parts::head_scan(model_->mesh, head(truth, 1.0, 9));
  ASSERT_TRUE(raw.ok());
  auto fit = calibrate_head(raw->points, *model_);
  ASSERT_TRUE(fit.ok()) << fit.message();
  EXPECT_EQ(fit->motion_scale, 1.0);
  const Recovery r = recovery(*fit, truth, 1.0, *raw);
  EXPECT_LT(r.rotation_deg, 0.01);
  EXPECT_LT(r.displacement_mm, 0.01);
}

// A head that sees only the flat base top (a plane), and one that sees only the +x chamfer and
// the base top (a profile extruded along y): refused, with the free directions named.
TEST_F(HeadCalibrationTest, RefusesAViewThatLeavesDirectionsFree) {
  const Transform nominal = parts::demo_heads()[0].nominal;
  parts::HeadScanSettings plane = head(nominal, 1.0, 3);
  plane.x_min_mm = 10;  // station x 90..130, y 25..45: the base top only
  plane.x_max_mm = 50;
  plane.encoder_min_mm = -25;
  plane.encoder_max_mm = -5;
  plane.outlier_fraction = 0.0;
  auto raw = parts::head_scan(model_->mesh, plane);
  ASSERT_TRUE(raw.ok());
  HeadCalibrationSettings settings;
  settings.use_initial_pose = true;
  settings.initial_pose = nominal;
  std::vector<CalibrationFreeDirection> free;
  auto fit = calibrate_head(raw->points, *model_, settings, &free);
  ASSERT_FALSE(fit.ok());
  EXPECT_TRUE(fit.error().is_analysis_failed());
  ASSERT_EQ(free.size(), 3u) << fit.message();
  int translations = 0;
  for (const auto& f : free) {
    if (f.rotation) {
      EXPECT_NEAR(std::abs(f.axis.z()), 1.0, 1e-6) << f.description;  // about the normal
    } else {
      ++translations;
      EXPECT_NEAR(f.axis.z(), 0.0, 1e-6) << f.description;  // in the plane
    }
  }
  EXPECT_EQ(translations, 2);
  EXPECT_NE(fit.message().find("translation along"), std::string::npos) << fit.message();

  parts::HeadScanSettings profile = plane;
  profile.x_min_mm = 40;  // station x 120..160 (base top and chamfer), y 25..45
  profile.x_max_mm = 80;
  raw = parts::head_scan(model_->mesh, profile);
  ASSERT_TRUE(raw.ok());
  fit = calibrate_head(raw->points, *model_, settings, &free);
  ASSERT_FALSE(fit.ok());
  ASSERT_EQ(free.size(), 1u) << fit.message();
  EXPECT_FALSE(free[0].rotation);
  EXPECT_NEAR(std::abs(free[0].axis.y()), 1.0, 1e-6) << free[0].description;
}

TEST_F(HeadCalibrationTest, EmptyAndTinyInputs) {
  EXPECT_FALSE(calibrate_head({}, *model_).ok());
  EXPECT_FALSE(calibrate_head(std::vector<Vec3>(50, Vec3(1, 2, 3)), *model_).ok());
  HeadCalibrationSettings bad;
  bad.motion_axis = 3;
  std::vector<Vec3> points(200, Vec3(1, 2, 3));
  EXPECT_TRUE(calibrate_head(points, *model_, bad).error().is_invalid_settings());
}

}  // namespace
}  // namespace springscan::analysis
