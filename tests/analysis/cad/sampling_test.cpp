#include "analysis/cad/sampling.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <numbers>

#include "simulators/parts/cad_profile.hpp"

namespace springscan::analysis {
using namespace springscan::parts;  // test and demo parts (simulators/parts)
namespace {

// Distance of a 3-D point to the profile's reference path (x-z plane), and the path's left
// normal there: the ground truth of a ProfileSpec shell.
struct PathFoot {
  double distance = 1e300;
  Eigen::Vector2d left = Eigen::Vector2d::Zero();
};

PathFoot foot_on_path(const ProfileSpec& spec, const Vec3& p) {
  const Eigen::Vector2d q(p.x(), p.z());
  PathFoot best;
  for (const auto& e : profile_path(spec)) {
    PathFoot f;
    if (e.kind == ProfileElement::Kind::kLine) {
      const Eigen::Vector2d d = (e.end - e.start).normalized();
      const double s = std::clamp((q - e.start).dot(d), 0.0, (e.end - e.start).norm());
      f.distance = (q - (e.start + s * d)).norm();
      f.left = Eigen::Vector2d(-d.y(), d.x());
    } else {
      const Eigen::Vector2d r = q - e.center;
      f.distance = std::abs(r.norm() - e.radius_mm);
      // Turning left the centre is on the left: the left normal points to the centre.
      f.left = (e.sweep_rad > 0 ? -1.0 : 1.0) * r.normalized();
    }
    if (f.distance < best.distance) best = f;
  }
  return best;
}

TEST(CadSampling, SamplesLieOnTheSurfaceWithExactNormals) {
  const ProfileSpec spec = hat_profile(20, 30, 40, 90, 4);
  const auto shape = make_profile_shape(spec);
  ASSERT_TRUE(shape) << shape.message();
  const auto cloud = sample_cad(*shape, {.sample_count = 5000});
  ASSERT_TRUE(cloud) << cloud.message();
  ASSERT_EQ(cloud->size(), 5000u);
  ASSERT_TRUE(cloud->attributes_consistent());
  ASSERT_TRUE(cloud->has_normals() && cloud->has_face_ids());
  double worst = 0.0, worst_normal = 0.0;
  int left = 0;
  for (std::size_t i = 0; i < cloud->size(); ++i) {
    const Vec3& p = cloud->points[i];
    const PathFoot foot = foot_on_path(spec, p);
    worst = std::max(worst, foot.distance);
    EXPECT_GE(p.y(), -1e-9);
    EXPECT_LE(p.y(), spec.width_mm + 1e-9);
    const Vec3& n = cloud->normals[i];
    const double along = n.x() * foot.left.x() + n.z() * foot.left.y();
    worst_normal = std::max(worst_normal, 1.0 - std::abs(along));
    left += along > 0 ? 1 : 0;
  }
  EXPECT_LT(worst, 1e-9);          // exactly on the surface, not on the chords
  EXPECT_LT(worst_normal, 1e-12);  // the surface normal, not the triangle's
  // One consistently oriented shell: every normal on the same side of the sheet.
  EXPECT_TRUE(left == 0 || left == static_cast<int>(cloud->size())) << left;
}

// With a thickness, the part is a solid and normals point out of it: on the reference side that
// is to the left of the path (the offset side lies to the right).
TEST(CadSampling, SolidNormalsPointOutward) {
  ProfileSpec spec = l_profile(40, 30, 90, 3);
  spec.thickness_mm = 2.0;
  const auto shape = make_profile_shape(spec);
  ASSERT_TRUE(shape) << shape.message();
  const auto cloud = sample_cad(*shape, {.sample_count = 4000});
  ASSERT_TRUE(cloud) << cloud.message();
  int checked = 0;
  for (std::size_t i = 0; i < cloud->size(); ++i) {
    const PathFoot foot = foot_on_path(spec, cloud->points[i]);
    const Vec3& n = cloud->normals[i];
    if (foot.distance > 1e-9 || std::abs(n.y()) > 0.5) continue;  // other faces
    EXPECT_GT(n.x() * foot.left.x() + n.z() * foot.left.y(), 0.999);
    ++checked;
  }
  EXPECT_GT(checked, 1000);
}

// Face f receives N * area_f / area_total samples (largest remainder), and within a flange the
// samples are uniform: each quarter of the face holds a binomial share within 4 sigma.
TEST(CadSampling, EvenByArea) {
  const ProfileSpec spec = l_profile(40, 30, 90, 3);
  const auto shape = make_profile_shape(spec);
  ASSERT_TRUE(shape) << shape.message();
  const int n = 20000;
  const auto cloud = sample_cad(*shape, {.sample_count = n});
  ASSERT_TRUE(cloud) << cloud.message();
  std::map<int, int> per_face;
  for (int id : cloud->face_ids) ++per_face[id];
  ASSERT_EQ(per_face.size(), 3u);
  const double arc = 3 * std::numbers::pi / 2, total = 40 + 30 + arc;
  std::vector<int> counts;
  for (const auto& [id, count] : per_face) counts.push_back(count);
  std::sort(counts.begin(), counts.end());
  // Exact areas 30 w, 40 w and 4.71 w; the chordal mesh area differs by < 1e-3 relative.
  EXPECT_NEAR(counts[0], n * arc / total, 2.0 + 1e-3 * n * arc / total);
  EXPECT_NEAR(counts[1], n * 30 / total, 2.0);
  EXPECT_NEAR(counts[2], n * 40 / total, 2.0);
  // Quarters of the 40 mm flange (z = 0, 0 <= x <= 40, 0 <= y <= 60).
  int quarter[4] = {0, 0, 0, 0};
  int on_flange = 0;
  for (const auto& p : cloud->points) {
    if (std::abs(p.z()) > 1e-9 || p.x() > 40.0) continue;
    ++on_flange;
    ++quarter[(p.x() < 20.0 ? 0 : 1) + (p.y() < 30.0 ? 0 : 2)];
  }
  const double expected = on_flange / 4.0, sigma = std::sqrt(on_flange * 0.25 * 0.75);
  for (int q : quarter) EXPECT_NEAR(q, expected, 4 * sigma);
}

TEST(CadSampling, EmptyAndTinyAndDeterministic) {
  const auto shape = make_profile_shape(l_profile(40, 30, 90, 3));
  ASSERT_TRUE(shape);
  const auto none = sample_cad(*shape, {.sample_count = 0});
  ASSERT_TRUE(none);
  EXPECT_TRUE(none->empty());
  const auto one = sample_cad(*shape, {.sample_count = 1});
  ASSERT_TRUE(one);
  EXPECT_EQ(one->size(), 1u);
  EXPECT_FALSE(sample_cad(*shape, {.sample_count = -1}));
  EXPECT_FALSE(sample_cad(CadShape{}));
  const auto a = sample_cad(*shape, {.sample_count = 100, .seed = 7});
  const auto b = sample_cad(*shape, {.sample_count = 100, .seed = 7});
  ASSERT_TRUE(a && b);
  EXPECT_EQ(a->points, b->points);
}

}  // namespace
}  // namespace springscan::analysis
