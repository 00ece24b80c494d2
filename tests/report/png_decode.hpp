#pragma once
// A PNG decoder for the tests only (8-bit RGB and RGBA, no interlace, all five filters): it
// checks our encoder independently and reads Chromium's screenshots. zlib inflates.

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace springscan::report::testing {

struct DecodedPng {
  int width = 0;
  int height = 0;
  int channels = 0;                  ///< 3 (RGB) or 4 (RGBA)
  std::vector<std::uint8_t> pixels;  ///< rows top to bottom, `channels` bytes per pixel
};

/// The decoded image, or nullopt with the reason in *error: bad signature, a chunk whose
/// CRC does not match, an unsupported format, or a stream that does not inflate to the size
/// IHDR implies.
std::optional<DecodedPng> decode_png(std::string_view bytes, std::string* error = nullptr);

}  // namespace springscan::report::testing
