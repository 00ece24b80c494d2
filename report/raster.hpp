#pragma once
// Point-splat rendering of a (reduced) cloud into an RGB raster with a z-buffer: the pictures
// of the report are drawn from at most ~100k points, so a 1M-point scan costs no more to show
// than a 100k one (the report has 300 ms).

#include <cstdint>
#include <vector>

#include "report/png.hpp"
#include "report/view.hpp"

namespace springscan::report {

/// Indices of at most `max_points` of `count` points, chosen uniformly at random with a fixed
/// seed (so the same report renders the same pictures), in increasing order, no repeats.
/// All indices when count <= max_points. Cost O(max_points log max_points).
std::vector<std::uint32_t> subsample_indices(std::size_t count, std::size_t max_points,
                                             std::uint32_t seed = 1);

struct SplatSettings {
  int radius_px = 1;  ///< each point covers a (2r+1) x (2r+1) square
  Rgb background = {255, 255, 255};
  double shading = 0.35;  ///< 0: flat colours; up to 1: darken where depth changes fast
};

/// Draws `points` with `colors` (one per point) into a new image of the view's size; the
/// nearest point wins each pixel. Shading darkens pixels by the local depth slope (a
/// screen-space stand-in for surface normals, which a deviation cloud need not carry), so
/// bends and flanges read as shapes. Non-finite points are skipped. Pure function.
RgbImage render_points(const std::vector<Vec3>& points, const std::vector<Rgb>& colors,
                       const ViewProjection& view, const SplatSettings& settings = {});

}  // namespace springscan::report
