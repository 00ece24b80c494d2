#include "tests/report/png_decode.hpp"

#include <zlib.h>

#include <cstdlib>

namespace springscan::report::testing {
namespace {

std::uint32_t read_u32(std::string_view b, std::size_t at) {
  return (std::uint32_t{static_cast<std::uint8_t>(b[at])} << 24) |
         (std::uint32_t{static_cast<std::uint8_t>(b[at + 1])} << 16) |
         (std::uint32_t{static_cast<std::uint8_t>(b[at + 2])} << 8) |
         std::uint32_t{static_cast<std::uint8_t>(b[at + 3])};
}

std::uint8_t paeth(int a, int b, int c) {
  const int p = a + b - c, pa = std::abs(p - a), pb = std::abs(p - b), pc = std::abs(p - c);
  return static_cast<std::uint8_t>(pa <= pb && pa <= pc ? a : pb <= pc ? b : c);
}

// Undoes the per-row filters (PNG spec section 9) in place into `out`.
bool unfilter(const std::string& raw, DecodedPng& img) {
  const std::size_t bpp = static_cast<std::size_t>(img.channels);
  const std::size_t row = static_cast<std::size_t>(img.width) * bpp;
  if (raw.size() != (row + 1) * static_cast<std::size_t>(img.height)) return false;
  img.pixels.assign(row * static_cast<std::size_t>(img.height), 0);
  for (std::size_t y = 0; y < static_cast<std::size_t>(img.height); ++y) {
    const auto filter = static_cast<std::uint8_t>(raw[y * (row + 1)]);
    const char* in = raw.data() + y * (row + 1) + 1;
    std::uint8_t* out = img.pixels.data() + y * row;
    const std::uint8_t* up = y > 0 ? out - row : nullptr;
    for (std::size_t i = 0; i < row; ++i) {
      const int a = i >= bpp ? out[i - bpp] : 0, b = up ? up[i] : 0,
                c = (up && i >= bpp) ? up[i - bpp] : 0;
      const auto x = static_cast<std::uint8_t>(in[i]);
      int predictor = 0;
      switch (filter) {
        case 0:
          predictor = 0;
          break;
        case 1:
          predictor = a;
          break;
        case 2:
          predictor = b;
          break;
        case 3:
          predictor = (a + b) / 2;
          break;
        case 4:
          predictor = paeth(a, b, c);
          break;
        default:
          return false;
      }
      out[i] = static_cast<std::uint8_t>(x + predictor);
    }
  }
  return true;
}

std::optional<DecodedPng> failed(std::string* error, const std::string& why) {
  if (error) *error = why;
  return std::nullopt;
}

}  // namespace

std::optional<DecodedPng> decode_png(std::string_view b, std::string* error) {
  if (b.size() < 8 || b.substr(0, 8) != std::string_view("\x89PNG\r\n\x1a\n", 8))
    return failed(error, "bad signature");
  DecodedPng img;
  std::string idat;
  bool ended = false;
  for (std::size_t at = 8; at + 12 <= b.size() && !ended;) {
    const std::uint32_t length = read_u32(b, at);
    if (at + 12 + length > b.size()) return failed(error, "chunk runs past the end");
    const std::string_view type = b.substr(at + 4, 4), data = b.substr(at + 8, length);
    const uLong crc =
        crc32(crc32(0L, Z_NULL, 0), reinterpret_cast<const Bytef*>(b.data() + at + 4), 4 + length);
    if (crc != read_u32(b, at + 8 + length))
      return failed(error, "CRC mismatch in " + std::string(type));
    if (type == "IHDR") {
      img.width = static_cast<int>(read_u32(data, 0));
      img.height = static_cast<int>(read_u32(data, 4));
      const int depth = data[8], color = data[9], interlace = data[12];
      if (depth != 8 || (color != 2 && color != 6) || interlace != 0)
        return failed(error, "unsupported format");
      img.channels = color == 2 ? 3 : 4;
    } else if (type == "IDAT") {
      idat.append(data);
    } else if (type == "IEND") {
      ended = true;
    }
    at += 12 + length;
  }
  if (!ended || img.channels == 0) return failed(error, "missing IHDR or IEND");
  uLongf size = static_cast<uLongf>(
      (static_cast<std::size_t>(img.width) * static_cast<std::size_t>(img.channels) + 1) *
      static_cast<std::size_t>(img.height));
  std::string raw(size, '\0');
  if (uncompress(reinterpret_cast<Bytef*>(raw.data()), &size,
                 reinterpret_cast<const Bytef*>(idat.data()),
                 static_cast<uLong>(idat.size())) != Z_OK)
    return failed(error, "IDAT does not inflate");
  raw.resize(size);
  if (!unfilter(raw, img)) return failed(error, "bad filter or size");
  return img;
}

}  // namespace springscan::report::testing
