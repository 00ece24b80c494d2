#include "report/raster.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

namespace springscan::report {
namespace {

constexpr float kFar = std::numeric_limits<float>::infinity();

// Screen-space shading: the depth difference to the right and below neighbours, in mm per
// pixel, gives the surface slope; a Lambert term against a light from the upper left dims
// steep or shadowed pixels. Pixels at silhouettes (neighbour empty) are left as they are.
void shade(RgbImage& image, const std::vector<float>& depth, double mm_per_px, double amount) {
  if (amount <= 0.0) return;
  const int w = image.width, h = image.height;
  const Eigen::Vector3d light = Eigen::Vector3d(-0.4, -0.5, 1.0).normalized();
  for (int y = 0; y + 1 < h; ++y) {
    for (int x = 0; x + 1 < w; ++x) {
      const std::size_t i =
          static_cast<std::size_t>(y) * static_cast<std::size_t>(w) + static_cast<std::size_t>(x);
      const float d = depth[i], dx = depth[i + 1], dy = depth[i + static_cast<std::size_t>(w)];
      if (d == kFar || dx == kFar || dy == kFar) continue;
      // Normal of the depth surface z(x, y) in units where one pixel is mm_per_px mm; depth
      // grows away from the viewer, and image y grows downwards.
      const Eigen::Vector3d n =
          Eigen::Vector3d((dx - d) / mm_per_px, -(dy - d) / mm_per_px, 1.0).normalized();
      const double lit = std::clamp(n.dot(light), 0.0, 1.0);
      const double factor = 1.0 - amount * (1.0 - lit);
      const std::size_t o = i * 3;
      for (int c = 0; c < 3; ++c)
        image.rgb[o + static_cast<std::size_t>(c)] =
            static_cast<std::uint8_t>(image.rgb[o + static_cast<std::size_t>(c)] * factor);
    }
  }
}

}  // namespace

std::vector<std::uint32_t> subsample_indices(std::size_t count, std::size_t max_points,
                                             std::uint32_t seed) {
  std::vector<std::uint32_t> indices;
  if (count <= max_points) {
    indices.resize(count);
    for (std::size_t i = 0; i < count; ++i) indices[i] = static_cast<std::uint32_t>(i);
    return indices;
  }
  // Draw with replacement, then drop repeats: for max_points << count this keeps nearly all
  // draws, and costs no array of size `count` (a 1M-point scan needs no 1M shuffle).
  std::mt19937 rng(seed);
  std::uniform_int_distribution<std::size_t> pick(0, count - 1);
  indices.reserve(max_points);
  for (std::size_t i = 0; i < max_points; ++i)
    indices.push_back(static_cast<std::uint32_t>(pick(rng)));
  std::sort(indices.begin(), indices.end());
  indices.erase(std::unique(indices.begin(), indices.end()), indices.end());
  return indices;
}

RgbImage render_points(const std::vector<Vec3>& points, const std::vector<Rgb>& colors,
                       const ViewProjection& view, const SplatSettings& settings) {
  RgbImage image = RgbImage::filled(view.width_px, view.height_px, settings.background);
  const int w = image.width, h = image.height, r = std::max(settings.radius_px, 0);
  std::vector<float> depth(static_cast<std::size_t>(w) * static_cast<std::size_t>(h), kFar);
  const std::size_t n = std::min(points.size(), colors.size());
  for (std::size_t k = 0; k < n; ++k) {
    const Eigen::Vector2d px = view.to_pixel(points[k]);
    const double z = view.depth(points[k]);
    // Off-image (or NaN) points are dropped before the cast to int, which could overflow.
    if (!(px.x() > -r - 1.0 && px.x() < w + r + 1.0 && px.y() > -r - 1.0 && px.y() < h + r + 1.0 &&
          std::isfinite(z)))
      continue;
    const int cx = static_cast<int>(std::floor(px.x())), cy = static_cast<int>(std::floor(px.y()));
    const float zf = static_cast<float>(z);
    for (int y = std::max(cy - r, 0); y <= std::min(cy + r, h - 1); ++y) {
      for (int x = std::max(cx - r, 0); x <= std::min(cx + r, w - 1); ++x) {
        const std::size_t i =
            static_cast<std::size_t>(y) * static_cast<std::size_t>(w) + static_cast<std::size_t>(x);
        if (zf >= depth[i]) continue;
        depth[i] = zf;
        image.set(x, y, colors[k]);
      }
    }
  }
  shade(image, depth, 1.0 / view.scale_px_per_mm, settings.shading);
  return image;
}

}  // namespace springscan::report
