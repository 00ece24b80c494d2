// Projections put known points at known pixels; the z-buffer keeps the nearest point; the
// subsample and the colour scale behave as documented.
#include "report/view.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <set>

#include "report/colormap.hpp"
#include "report/raster.hpp"

namespace springscan::report {
namespace {

void expect_pixel(const ViewProjection& view, const Vec3& p, double x, double y) {
  const Eigen::Vector2d px = view.to_pixel(p);
  EXPECT_NEAR(px.x(), x, 1e-9) << p.transpose();
  EXPECT_NEAR(px.y(), y, 1e-9) << p.transpose();
}

// A 100 x 50 x 20 mm box's corners, starting at (10, 20, 30).
std::vector<Vec3> box_corners() {
  std::vector<Vec3> corners;
  for (int i = 0; i < 8; ++i)
    corners.emplace_back(10 + 100 * (i & 1), 20 + 50 * ((i >> 1) & 1), 30 + 20 * ((i >> 2) & 1));
  return corners;
}

TEST(View, TopViewMapsXRightAndYUp) {
  // 220 x 120 image, margin 10: 200 x 100 free, so 2 px/mm for a 100 x 50 footprint.
  const auto view = fit_view(box_corners(), ViewKind::kTop, {220, 120, 10});
  EXPECT_DOUBLE_EQ(view.scale_px_per_mm, 2.0);
  expect_pixel(view, {10, 20, 30}, 10, 110);                  // x min, y min: lower left
  expect_pixel(view, {110, 70, 50}, 210, 10);                 // upper right
  expect_pixel(view, {60, 45, 0}, 110, 60);                   // centre, any height
  EXPECT_LT(view.depth({0, 0, 50}), view.depth({0, 0, 30}));  // higher is nearer from above
}

TEST(View, FrontViewMapsXRightAndZUp) {
  // 100 x 20 mm in x-z: the width limits the scale, 200 / 100 = 2 px/mm.
  const auto view = fit_view(box_corners(), ViewKind::kFront, {220, 120, 10});
  EXPECT_DOUBLE_EQ(view.scale_px_per_mm, 2.0);
  expect_pixel(view, {10, 99, 30}, 10, 60 + 20);
  expect_pixel(view, {110, -5, 50}, 210, 60 - 20);
  EXPECT_LT(view.depth({0, 20, 0}), view.depth({0, 70, 0}));  // -y side faces the viewer
}

TEST(View, SideViewMapsYRightAndZUp) {
  // 50 x 20 mm in y-z; 200 / 50 = 4 and 100 / 20 = 5 px/mm: 4 wins.
  const auto view = fit_view(box_corners(), ViewKind::kSide, {220, 120, 10});
  EXPECT_DOUBLE_EQ(view.scale_px_per_mm, 4.0);
  expect_pixel(view, {0, 20, 30}, 10, 60 + 40);
  expect_pixel(view, {0, 70, 50}, 210, 60 - 40);
  EXPECT_LT(view.depth({110, 0, 0}), view.depth({10, 0, 0}));  // seen from +x
}

TEST(View, IsometricSeesTheCubeCornerOnItsCentre) {
  const auto basis = view_basis(ViewKind::kIsometric);
  EXPECT_TRUE(basis.right.isApprox(Vec3(1, 1, 0).normalized()));
  EXPECT_NEAR(basis.up.z(), std::sqrt(2.0 / 3.0), 1e-12);
  EXPECT_TRUE(basis.right.cross(basis.up).isApprox(-basis.forward));
  // Points on the viewing ray through the centre land on the same pixel.
  std::vector<Vec3> cube = {{-1, -1, -1}, {1, 1, 1}};
  const auto view = fit_view(cube, ViewKind::kIsometric, {200, 200, 0});
  const Vec3 towards_viewer = -basis.forward;
  expect_pixel(view, Vec3::Zero(), 100, 100);
  expect_pixel(view, 3.0 * towards_viewer, 100, 100);
  EXPECT_LT(view.depth(towards_viewer), view.depth(Vec3::Zero()));
}

TEST(Raster, NearestPointWinsEachPixel) {
  for (auto kind : {ViewKind::kTop, ViewKind::kFront, ViewKind::kSide, ViewKind::kIsometric}) {
    const auto basis = view_basis(kind);
    const Vec3 centre(5, 5, 5);
    // Two points on one viewing ray: the one towards the viewer must show.
    const std::vector<Vec3> points = {centre + 2.0 * basis.forward, centre - 2.0 * basis.forward,
                                      centre + 40 * basis.right, centre - 40 * basis.right};
    const std::vector<Rgb> colors = {{0, 0, 255}, {255, 0, 0}, {0, 0, 0}, {0, 0, 0}};
    const auto view = fit_view(points, kind, {101, 51, 10});
    const auto image = render_points(points, colors, view, {0, {255, 255, 255}, 0.0});
    const Eigen::Vector2d px = view.to_pixel(centre);
    EXPECT_EQ(image.at(static_cast<int>(px.x()), static_cast<int>(px.y())), (Rgb{255, 0, 0}))
        << view_name(kind);
  }
}

TEST(Raster, SplatCoversItsSquareAndNothingElse) {
  const std::vector<Vec3> points = {{0, 0, 0}, {10, 10, 0}};
  const auto view = fit_view(points, ViewKind::kTop, {41, 41, 10});  // 2.1 px/mm
  const auto image = render_points({{5, 5, 0}}, {{10, 20, 30}}, view, {2, {255, 255, 255}, 0.0});
  const Eigen::Vector2d px = view.to_pixel({5, 5, 0});
  const int cx = static_cast<int>(px.x()), cy = static_cast<int>(px.y());
  int painted = 0;
  for (int y = 0; y < image.height; ++y)
    for (int x = 0; x < image.width; ++x)
      if (image.at(x, y) == Rgb{10, 20, 30}) {
        ++painted;
        EXPECT_LE(std::abs(x - cx), 2);
        EXPECT_LE(std::abs(y - cy), 2);
      }
  EXPECT_EQ(painted, 25);
}

TEST(Raster, EmptyCloudGivesBackground) {
  const auto view = fit_view({}, ViewKind::kTop, {8, 6, 1});
  const auto image = render_points({}, {}, view);
  EXPECT_EQ(image.width, 8);
  EXPECT_EQ(image.at(3, 3), (Rgb{255, 255, 255}));
}

TEST(Subsample, KeepsAllOrAFixedSortedUniqueSubset) {
  EXPECT_EQ(subsample_indices(5, 10).size(), 5u);
  EXPECT_TRUE(subsample_indices(0, 10).empty());
  const auto a = subsample_indices(1'000'000, 1000, 3), b = subsample_indices(1'000'000, 1000, 3);
  EXPECT_EQ(a, b);
  EXPECT_GT(a.size(), 990u);  // few repeats when drawing 1000 of 1M
  EXPECT_LE(a.size(), 1000u);
  EXPECT_TRUE(std::is_sorted(a.begin(), a.end()));
  EXPECT_EQ(std::set<std::uint32_t>(a.begin(), a.end()).size(), a.size());
  EXPECT_LT(a.back(), 1'000'000u);
  EXPECT_GT(a.back(), 900'000u);  // spread over the whole range
}

TEST(ColorMap, BlueGreenRedWithClampAndGreyForNaN) {
  const Rgb blue = deviation_color(-1.0, 1.0), green = deviation_color(0.0, 1.0),
            red = deviation_color(1.0, 1.0);
  EXPECT_GT(blue[2], blue[0]);
  EXPECT_GT(green[1], green[0]);
  EXPECT_GT(green[1], green[2]);
  EXPECT_GT(red[0], red[2]);
  EXPECT_EQ(deviation_color(-5.0, 1.0), blue);
  EXPECT_EQ(deviation_color(5.0, 1.0), red);
  EXPECT_EQ(deviation_color(std::nan(""), 1.0), (Rgb{150, 150, 150}));
  EXPECT_EQ(css_color({255, 0, 16}), "#ff0010");
}

}  // namespace
}  // namespace springscan::report
