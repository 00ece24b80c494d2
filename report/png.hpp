#pragma once
// A small PNG encoder (ISO/IEC 15948, 8-bit truecolour, no interlace) for the pictures the
// HTML report embeds as data: URIs. zlib does the deflate and the CRCs.

#include <cstdint>
#include <string>
#include <vector>

#include "analysis/core/expected.hpp"
#include "analysis/core/point_cloud.hpp"

namespace springscan::report {

using analysis::Rgb;

/// An 8-bit RGB raster, rows top to bottom, 3 bytes per pixel. Plain value type.
struct RgbImage {
  int width = 0;
  int height = 0;
  std::vector<std::uint8_t> rgb;  ///< width * height * 3 bytes

  /// A width x height image filled with `fill`; sizes below 0 count as 0.
  static RgbImage filled(int width, int height, Rgb fill);
  std::size_t offset(int x, int y) const {
    return (static_cast<std::size_t>(y) * static_cast<std::size_t>(width) +
            static_cast<std::size_t>(x)) *
           3;
  }
  Rgb at(int x, int y) const {
    const std::size_t o = offset(x, y);
    return {rgb[o], rgb[o + 1], rgb[o + 2]};
  }
  void set(int x, int y, Rgb c) {
    const std::size_t o = offset(x, y);
    rgb[o] = c[0];
    rgb[o + 1] = c[1];
    rgb[o + 2] = c[2];
  }
};

struct PngSettings {
  int compression_level = 6;  ///< zlib level 0 (store) .. 9 (smallest); 6 is zlib's default
};

/// Encodes the image as a PNG file (the bytes). Every row uses the "Up" filter (PNG spec
/// section 9.2), which suits the flat areas of rendered views. Errors: an empty image, a
/// pixel buffer whose size disagrees with width x height, or a zlib failure.
/// Thread-safe: no shared state.
analysis::Expected<std::string> encode_png(const RgbImage& image, const PngSettings& settings = {});

}  // namespace springscan::report
