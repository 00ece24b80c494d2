// Beyond rigid flanges, end to end through measure_springback: shaped parts built by
// simulators/parts/shaped_profile.hpp with their truth in closed form, scanned (sigma 0.02 mm),
// placed by the global fit, measured.
#include "analysis/springback/bend_shape.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numbers>
#include <random>

#include "analysis/registration/global_fit.hpp"
#include "simulators/parts/shaped_profile.hpp"
#include "tests/analysis/under_sanitizer.hpp"

namespace springscan::analysis {
using namespace springscan::parts;  // test and demo parts (simulators/parts)
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;
using testing::kUnderSanitizer;
constexpr int kTrials = kUnderSanitizer ? 1 : 4;

Transform random_pose(std::mt19937& rng, double angle_rad, double shift_mm) {
  std::normal_distribution<double> g;
  const Vec3 axis = Vec3(g(rng), g(rng), g(rng)).normalized();
  return Eigen::Translation3d(shift_mm * Vec3(g(rng), g(rng), g(rng)).normalized()) *
         Eigen::AngleAxisd(angle_rad, axis);
}

// The shaped scan in a random scanner pose, brought back with a pose error of 1 deg and 1 mm
// and refined by the global fit (ICP, no PCA: the hat and U are symmetric). `T_cad_part`: where
// the fit put the part (a profile's length is a free direction: the fit may slide it along y,
// and a station's truth is the part's own y there).
PointCloud scan_in_cad(const ProfileSpec& spec, const ProfileShape& shape, const PartModel& model,
                       std::int64_t points, std::mt19937& rng, Transform* T_cad_part = nullptr) {
  ScanSimulationSettings st;
  st.point_count = points;
  st.noise_sigma_mm = 0.02;
  st.seed = rng();
  st.T_scan_part = random_pose(rng, 2.0, 200.0);
  const auto scan = simulate_shaped_scan(spec, shape, st);
  EXPECT_TRUE(scan.ok()) << scan.message();
  const Transform error = random_pose(rng, kDeg, 1.0);
  const PointCloud cloud = transformed(*scan, error * st.T_scan_part.inverse());
  const KdTree tree(model.samples.points);
  GlobalFitSettings settings;
  settings.pca_initial_alignment = false;
  const auto global = global_fit(cloud.points, tree, model.samples.normals, settings);
  EXPECT_TRUE(global.ok()) << global.message();
  if (T_cad_part) *T_cad_part = global->T_cad_scan * error;
  return transformed(cloud, global->T_cad_scan);
}

Expected<SpringbackResult> measure(const ProfileSpec& spec, const ProfileShape& shape,
                                   std::int64_t points, std::mt19937& rng,
                                   Transform* T_cad_part = nullptr) {
  const auto model = profile_part_model(spec, {.sample_count = 40000});
  if (!model) return model.error();
  return measure_springback(*model, scan_in_cad(spec, shape, *model, points, rng, T_cad_part));
}

ProfileSpec random_profile(char kind, double width, std::mt19937& rng) {
  std::uniform_real_distribution<double> length(25, 60), radius(2, 8), angle(60, 95);
  const double a = angle(rng), r = radius(rng);
  ProfileSpec spec = kind == 'L'   ? l_profile(length(rng), length(rng), a, r)
                     : kind == 'U' ? u_profile(length(rng), length(rng), a, r)
                                   : hat_profile(length(rng), length(rng), length(rng), a, r);
  spec.width_mm = width;
  return spec;
}

// Springback varying linearly by 0.5-2 deg along a 200 mm bend: each station within 0.05 deg
// of the angle the bend turns there.
TEST(BendShape, AngleAlongTheBendFollowsALinearSpringbackWithin005Deg) {
  std::mt19937 rng(31);
  std::uniform_real_distribution<double> change(0.5, 2.0), springback(-0.5, 2.5), coin(0, 1);
  double worst = 0.0;
  for (int trial = 0; trial < kTrials; ++trial) {
    const char kind = "LUH"[trial % 3];
    const ProfileSpec spec = random_profile(kind, 200.0, rng);
    ProfileShape shape;
    for (std::size_t b = 0; b < spec.bend_angles_deg.size(); ++b) {
      shape.springback_deg.push_back(springback(rng));
      shape.springback_gradient_deg_per_100mm.push_back((coin(rng) < 0.5 ? -0.5 : 0.5) *
                                                        change(rng));
    }
    Transform T_cad_part;
    const auto result = measure(spec, shape, 80000, rng, &T_cad_part);
    ASSERT_TRUE(result.ok()) << result.message();
    for (std::size_t b = 0; b < result->bends.size(); ++b) {
      const BendMeasurement& m = result->bends[b];
      ASSERT_TRUE(m.measured) << m.status;
      ASSERT_EQ(m.stations.size(), 10u) << "200 mm at 20 mm";
      for (const BendStation& s : m.stations) {
        const double y =
            (T_cad_part.inverse() * (m.axis_point + s.position_mm * m.axis_direction)).y();
        const double truth = shaped_bend_angle_deg(spec, shape, static_cast<int>(b), y);
        EXPECT_NEAR(s.angle_deg, truth, 0.05) << kind << " bend " << b << " y " << y;
        EXPECT_NEAR(s.springback_deg, m.nominal_angle_deg - truth, 0.05);
        worst = std::max(worst, std::abs(s.angle_deg - truth));
      }
      const double ends = shaped_bend_angle_deg(spec, shape, static_cast<int>(b), 200.0) -
                          shaped_bend_angle_deg(spec, shape, static_cast<int>(b), 0.0);
      EXPECT_NEAR(m.angle_spread_deg, std::abs(ends) * 0.9, 0.1) << "stations 10..190 mm";
      EXPECT_GT(m.angle_twist_deg * ends * (m.axis_direction.y() > 0 ? 1 : -1), 0.0);
    }
  }
  std::printf("angle along the bend: worst station error %.4f deg\n", worst);
}

// Bend radius: the cylinder of one side of the sheet in each bend zone.
TEST(BendShape, MeasuredBendRadiusWithin2Percent) {
  std::mt19937 rng(32);
  double worst = 0.0;
  for (int trial = 0; trial < kTrials; ++trial) {
    const char kind = "LUH"[trial % 3];
    const ProfileSpec spec = random_profile(kind, 80.0, rng);
    ProfileShape shape;
    shape.springback_deg.assign(spec.bend_angles_deg.size(), 1.0);
    const auto result = measure(spec, shape, 60000, rng);
    ASSERT_TRUE(result.ok()) << result.message();
    for (const BendMeasurement& m : result->bends) {
      ASSERT_TRUE(m.zone.fitted);
      const double error = std::abs(m.measured_radius_mm / m.radius_mm - 1.0);
      EXPECT_LT(error, 0.02) << kind << " bend " << m.bend_id << " r " << m.radius_mm;
      worst = std::max(worst, error);
    }
  }
  std::printf("bend radius: worst relative error %.4f\n", worst);
}

// NUMISHEET'93 on a hat: sidewall curl rho = 150-1000 mm on 40-80 mm walls within 3 %, the bend
// angles by the tangent planes at the walls' ends within 0.05 deg, a flat wall flat.
TEST(BendShape, CurledHatWallsRadiusWithin3PercentAndEndAnglesWithin005Deg) {
  std::mt19937 rng(33);
  std::uniform_real_distribution<double> wall(40, 80), rho(150, 1000), coin(0, 1), spring(0, 2);
  double worst_rho = 0.0, worst_angle = 0.0;
  for (int trial = 0; trial < kTrials; ++trial) {
    // The ends of the range first: the tightest curl on the longest wall, the loosest on the
    // shortest.
    const double length = trial == 0 ? 80 : trial == 1 ? 40 : wall(rng);
    const double magnitude = trial == 0 ? 150 : trial == 1 ? 1000 : rho(rng);
    ProfileSpec spec = hat_profile(30, length, 50, 90, 5);
    spec.width_mm = 80;
    ProfileShape shape;
    for (int b = 0; b < 4; ++b) shape.springback_deg.push_back(spring(rng));
    // One wall curled (either way), the other flat.
    const double radius = (coin(rng) < 0.5 ? -1 : 1) * magnitude;
    const int curled = trial % 2 == 0 ? 1 : 3;
    shape.curl_radius_mm = {0, 0, 0, 0, 0};
    shape.curl_radius_mm[static_cast<std::size_t>(curled)] = radius;
    const auto result = measure(spec, shape, 80000, rng);
    ASSERT_TRUE(result.ok()) << result.message();
    for (int f = 0; f < 5; ++f) {
      const FlangeShape& s = result->flanges[static_cast<std::size_t>(f)].shape;
      ASSERT_TRUE(s.measured);
      if (f != curled) {
        EXPECT_FALSE(s.curled) << "flange " << f << " reported curl " << s.curl_radius_mm;
        continue;
      }
      ASSERT_TRUE(s.curled) << "wall " << f << " rho " << radius;
      EXPECT_NEAR(s.curl_radius_mm / radius, 1.0, 0.03) << "wall " << f << " rho " << radius;
      worst_rho = std::max(worst_rho, std::abs(s.curl_radius_mm / radius - 1.0));
    }
    for (int b = 0; b < 4; ++b) {
      const BendMeasurement& m = result->bends[static_cast<std::size_t>(b)];
      const double truth = shaped_bend_angle_deg(spec, shape, b, 40.0);
      const bool next_to_curl = b == curled - 1 || b == curled;
      EXPECT_EQ(m.end_tangents, next_to_curl) << "bend " << b;
      EXPECT_NEAR(m.measured_angle_deg, truth, 0.05) << "bend " << b << " rho " << radius;
      worst_angle = std::max(worst_angle, std::abs(m.measured_angle_deg - truth));
      if (next_to_curl) {  // the plane through the whole wall is off (the reason for the rule)
        EXPECT_GT(std::abs(m.plane_angle_deg - truth), 0.5) << "bend " << b;
      }
    }
  }
  std::printf("curl: worst rho error %.4f, worst end-tangent angle error %.4f deg\n", worst_rho,
              worst_angle);
}

// Twist 0.2-1 deg per 100 mm (of the whole section, or of the flanges past a bend whose
// springback changes along it) within 0.03 deg per 100 mm.
TEST(BendShape, TwistWithin003DegPer100mm) {
  std::mt19937 rng(34);
  std::uniform_real_distribution<double> twist(0.2, 1.0), coin(0, 1);
  double worst = 0.0;
  for (int trial = 0; trial < kTrials; ++trial) {
    const char kind = "LUH"[trial % 3];
    const ProfileSpec spec = random_profile(kind, 200.0, rng);
    ProfileShape shape;
    shape.springback_deg.assign(spec.bend_angles_deg.size(), 1.0);
    shape.springback_gradient_deg_per_100mm.assign(spec.bend_angles_deg.size(), 0.0);
    if (trial % 2 == 0)
      shape.twist_deg_per_100mm = (coin(rng) < 0.5 ? -1 : 1) * twist(rng);
    else  // the last flange twists against the rest
      shape.springback_gradient_deg_per_100mm.back() = (coin(rng) < 0.5 ? -1 : 1) * twist(rng);
    const auto result = measure(spec, shape, 80000, rng);
    ASSERT_TRUE(result.ok()) << result.message();
    for (std::size_t f = 0; f < result->flanges.size(); ++f) {
      const FlangeShape& s = result->flanges[f].shape;
      ASSERT_TRUE(s.measured);
      const double truth = shaped_flange_twist_deg_per_100mm(spec, shape, static_cast<int>(f));
      EXPECT_NEAR(s.twist_deg_per_100mm, truth, 0.03) << kind << " flange " << f;
      worst = std::max(worst, std::abs(s.twist_deg_per_100mm - truth));
      EXPECT_FALSE(s.curled) << kind << " flange " << f;
    }
  }
  std::printf("twist: worst error %.4f deg/100 mm\n", worst);
}

TEST(BendShape, FlatFlangeFlatnessIsTheNoise) {
  std::mt19937 rng(35);
  const ProfileSpec spec = l_profile(50, 40, 90, 3);
  ProfileShape shape;
  shape.springback_deg = {1.0};
  const auto result = measure(spec, shape, 40000, rng);
  ASSERT_TRUE(result.ok());
  for (const FlangeFit& f : result->flanges) {
    EXPECT_NEAR(f.shape.flatness_rms_mm, 0.02, 0.003);
    EXPECT_LT(f.shape.flatness_max_mm, 0.12);
    EXPECT_FALSE(f.shape.curled);
    EXPECT_TRUE(std::isinf(f.shape.curl_radius_mm));
    EXPECT_TRUE(f.shape.twist_measured);
  }
  // A 20 mm wide L: too short along its bend line for a twist.
  ProfileSpec narrow = spec;
  narrow.width_mm = 20;
  const auto short_result = measure(narrow, shape, 20000, rng);
  ASSERT_TRUE(short_result.ok());
  for (const FlangeFit& f : short_result->flanges) {
    EXPECT_TRUE(f.shape.measured);
    EXPECT_FALSE(f.shape.twist_measured);
  }
  EXPECT_EQ(result->bends[0].stations.size(), 3u) << "60 mm at 20 mm";
  EXPECT_FALSE(result->bends[0].end_tangents);
  EXPECT_EQ(result->bends[0].measured_angle_deg, result->bends[0].plane_angle_deg);
}

// The free edges of a hat's brims against the CAD edges: the last brim 0.3 mm longer (or
// shorter) and turned by its bend so that its edge sits 0.5 mm off; the global fit then places
// the part as it can. Each strip's truth from the exact sections, the part placed where the
// global fit put it; the edge's min, mean and max each within 0.05 mm.
TEST(BendShape, FreeEdgeInPlaneAndAcrossWithin005mm) {
  std::mt19937 rng(36);
  double worst = 0.0;
  for (int trial = 0; trial < (kUnderSanitizer ? 1 : 3); ++trial) {
    ProfileSpec spec = hat_profile(30 + 5 * trial, 40, 50, 90, 4);
    spec.width_mm = 120;
    ProfileShape shape;
    // Turning the brim about its bend by atan(0.5 / arm) moves its edge 0.5 mm across.
    const double arm = spec.flange_lengths_mm.back() + spec.bend_radii_mm.back();
    shape.springback_deg = {0, 0, 0, std::atan(0.5 / arm) / kDeg * (trial == 1 ? -1 : 1)};
    shape.length_change_mm = {0, 0, 0, 0, trial == 2 ? -0.3 : 0.3};
    Transform T_cad_part;
    const auto result = measure(spec, shape, 100000, rng, &T_cad_part);
    ASSERT_TRUE(result.ok()) << result.message();
    const auto nominal = profile_path(spec);
    // Each brim's free edge: the path's start (flange 0) and end (flange 4), 6 strips of 20 mm.
    for (const bool last : {false, true}) {
      const ProfileElement& n = last ? nominal.back() : nominal.front();
      const Eigen::Vector2d dir2 = (n.end - n.start).normalized() * (last ? 1.0 : -1.0);
      const Vec3 out = profile_to_3d(dir2, 0.0);
      // The reference side's normal: left of the path.
      const Vec3 normal =
          profile_to_3d(Eigen::Vector2d(-dir2.y(), dir2.x()), 0.0) * (last ? 1.0 : -1.0);
      Eigen::Vector2d in_truth(1e9, -1e9), across_truth(1e9, -1e9);
      double in_mean = 0.0, across_mean = 0.0;
      for (int k = 0; k < 6; ++k) {
        const double y = 10.0 + 20.0 * k;
        const auto produced = shaped_section(spec, shape, y);
        ASSERT_TRUE(produced.ok());
        const Vec3 cad = profile_to_3d(last ? n.end : n.start, y);
        const Vec3 made =
            T_cad_part * profile_to_3d(last ? produced->back().end : produced->front().start, y);
        const double in = (made - cad).dot(out), across = (made - cad).dot(normal);
        in_truth = {std::min(in_truth[0], in), std::max(in_truth[1], in)};
        across_truth = {std::min(across_truth[0], across), std::max(across_truth[1], across)};
        in_mean += in / 6;
        across_mean += across / 6;
      }
      const EdgeDeviation* free = result->flanges[last ? 4 : 0].free_edge();
      ASSERT_NE(free, nullptr) << "flange " << (last ? 4 : 0);
      const EdgeDeviation& e = *free;
      EXPECT_EQ(e.strips, 6);
      // The drawn edges (report): at each strip's centre, the CAD edge on the CAD, and the
      // scan's edge where the produced part's edge is, across and along the sheet.
      ASSERT_EQ(e.cad_edge.size(), 6u);
      ASSERT_EQ(e.scan_edge.size(), 6u);
      for (std::size_t k = 0; k < 6; ++k) {
        const double y = e.cad_edge[k].y();
        EXPECT_LT((e.cad_edge[k] - profile_to_3d(last ? n.end : n.start, y)).norm(), 1e-6);
        const auto produced = shaped_section(spec, shape, y);
        ASSERT_TRUE(produced.ok());
        const Vec3 made =
            T_cad_part * profile_to_3d(last ? produced->back().end : produced->front().start, y);
        EXPECT_NEAR((e.scan_edge[k] - made).dot(out), 0.0, 0.05) << "strip " << k;
        EXPECT_NEAR((e.scan_edge[k] - made).dot(normal), 0.0, 0.05) << "strip " << k;
      }
      const double errors[] = {e.in_plane_min_mm - in_truth[0], e.in_plane_mean_mm - in_mean,
                               e.in_plane_max_mm - in_truth[1], e.across_min_mm - across_truth[0],
                               e.across_mean_mm - across_mean,  e.across_max_mm - across_truth[1]};
      for (double error : errors) {
        EXPECT_NEAR(error, 0.0, 0.05) << "flange " << (last ? 4 : 0) << " trial " << trial;
        worst = std::max(worst, std::abs(error));
      }
      if (last) {  // what the part was made with, as far as the global fit leaves it
        EXPECT_NEAR(std::abs(in_mean), 0.3, 0.1);
        EXPECT_GT(std::abs(across_mean), 0.2);
      }
    }
    for (int f = 1; f <= 3; ++f)
      EXPECT_EQ(result->flanges[static_cast<std::size_t>(f)].free_edge(), nullptr);
  }
  std::printf("free edge: worst error %.4f mm\n", worst);
}

// The side (trim) edges of a hat: every flange's edges at y = 0 and y = width, those at the
// width moved along y by a different amount per flange (overhang and draw-in), the brims' and
// web's turned by springback. The truth at each strip's centre: the material point of the CAD
// edge there (same arc length along its flange) on the produced section, placed where the
// global fit put the part; the scan's edge and the edge's mean within 0.05 mm of it.
TEST(BendShape, SideEdgesInPlaneAndAcrossWithin005mm) {
  std::mt19937 rng(37);
  double worst = 0.0;
  for (int trial = 0; trial < (kUnderSanitizer ? 1 : 2); ++trial) {
    ProfileSpec spec = hat_profile(30 + 5 * trial, 40, 50, 90, 4);
    spec.width_mm = 120;
    ProfileShape shape;
    shape.springback_deg = {1.0, -0.5, 1.5, 2.0};
    shape.width_change_mm = {0.3, -0.2, 0.5, 0.0, trial == 0 ? -0.4 : 0.25};
    Transform T_cad_part;
    const auto result = measure(spec, shape, 100000, rng, &T_cad_part);
    ASSERT_TRUE(result.ok()) << result.message();
    const auto nominal = profile_path(spec);
    const auto produced_at = [&](double y) {
      const auto section = shaped_section(spec, shape, y);
      EXPECT_TRUE(section.ok());
      return section.ok() ? *section : std::vector<ProfileElement>{};
    };
    int side_edges = 0;
    for (std::size_t f = 0; f < result->flanges.size(); ++f) {
      const ProfileElement& n = nominal[2 * f];
      ASSERT_EQ(n.flange_index, static_cast<int>(f));
      const Eigen::Vector2d dir = (n.end - n.start).normalized();
      const Vec3 normal = profile_to_3d(Eigen::Vector2d(-dir.y(), dir.x()), 0.0);
      for (const EdgeDeviation& e : result->flanges[f].trim_edges) {
        if (e.kind != EdgeKind::kSide) continue;
        ++side_edges;
        const bool far = e.cad_edge.front().y() > 0.5 * spec.width_mm;
        const double y_cad = far ? spec.width_mm : 0.0;
        const double y_made = far ? spec.width_mm + shape.width_change_mm[f] : 0.0;
        const Vec3 out = far ? Vec3::UnitY() : Vec3(-Vec3::UnitY());
        EXPECT_NEAR(e.outward.dot(out), 1.0, 1e-3) << "flange " << f;
        const std::vector<ProfileElement> made_section = produced_at(y_made);
        ASSERT_EQ(made_section.size(), nominal.size());
        const ProfileElement& m = made_section[2 * f];
        double in_mean = 0.0, across_mean = 0.0;
        for (std::size_t k = 0; k < e.cad_edge.size(); ++k) {
          const Vec3& cad = e.cad_edge[k];
          EXPECT_NEAR(cad.y(), y_cad, 1e-6) << "flange " << f << " strip " << k;
          const double u = (Eigen::Vector2d(cad.x(), cad.z()) - n.start).dot(dir);
          EXPECT_NEAR((profile_to_3d(n.start + u * dir, y_cad) - cad).norm(), 0.0, 1e-6);
          const Vec3 made =
              T_cad_part * profile_to_3d(m.start + u * (m.end - m.start).normalized(), y_made);
          const double in = (made - cad).dot(out), across = (made - cad).dot(normal);
          in_mean += in / static_cast<double>(e.cad_edge.size());
          across_mean += across / static_cast<double>(e.cad_edge.size());
          // The drawn points: one strip's share of a short edge's points (a 30 mm brim has
          // 3 strips of 10 mm), so looser than the edge's figures below.
          EXPECT_NEAR((e.scan_edge[k] - made).dot(out), 0.0, 0.08) << "flange " << f;
          EXPECT_NEAR((e.scan_edge[k] - made).dot(normal), 0.0, 0.08) << "flange " << f;
        }
        for (double error : {e.in_plane_mean_mm - in_mean, e.across_mean_mm - across_mean}) {
          EXPECT_NEAR(error, 0.0, 0.05) << "flange " << f << (far ? " far" : " near") << " side";
          worst = std::max(worst, std::abs(error));
        }
      }
    }
    EXPECT_EQ(side_edges, 10) << "two side edges on each of five flanges";
  }
  std::printf("side edges: worst error %.4f mm\n", worst);
}

TEST(BendShape, ResultDoesNotDependOnTheThreadCount) {
  const ProfileSpec spec = hat_profile(25, 40, 45, 90, 4);
  ProfileShape shape;
  shape.springback_deg = {1.0, 2.0, -0.5, 1.5};
  shape.springback_gradient_deg_per_100mm = {0.5, 0.0, -1.0, 0.25};
  shape.curl_radius_mm = {0, 300, 0, 0, 0};
  const auto model = profile_part_model(spec, {.sample_count = 20000});
  ASSERT_TRUE(model.ok());
  const auto scan = simulate_shaped_scan(spec, shape, {.point_count = 30000});
  ASSERT_TRUE(scan.ok());
  SpringbackSettings one, two;
  one.threads = 1;
  two.threads = 2;
  const auto a = measure_springback(*model, *scan, one);
  const auto b = measure_springback(*model, *scan, two);
  ASSERT_TRUE(a.ok() && b.ok());
  for (std::size_t i = 0; i < a->bends.size(); ++i) {
    EXPECT_EQ(a->bends[i].measured_angle_deg, b->bends[i].measured_angle_deg);
    EXPECT_EQ(a->bends[i].measured_radius_mm, b->bends[i].measured_radius_mm);
    ASSERT_EQ(a->bends[i].stations.size(), b->bends[i].stations.size());
    for (std::size_t k = 0; k < a->bends[i].stations.size(); ++k)
      EXPECT_EQ(a->bends[i].stations[k].angle_deg, b->bends[i].stations[k].angle_deg);
  }
  for (std::size_t f = 0; f < a->flanges.size(); ++f) {
    EXPECT_EQ(a->flanges[f].shape.curl_radius_mm, b->flanges[f].shape.curl_radius_mm);
    EXPECT_EQ(a->flanges[f].shape.flatness_max_mm, b->flanges[f].shape.flatness_max_mm);
  }
  EXPECT_TRUE(a->flanges[1].shape.curled);
}

}  // namespace
}  // namespace springscan::analysis
