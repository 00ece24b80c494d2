#include "report/png.hpp"

#include <zlib.h>

#include <algorithm>

namespace springscan::report {
namespace {

void put_u32(std::string& out, std::uint32_t value) {
  out.push_back(static_cast<char>((value >> 24) & 0xff));
  out.push_back(static_cast<char>((value >> 16) & 0xff));
  out.push_back(static_cast<char>((value >> 8) & 0xff));
  out.push_back(static_cast<char>(value & 0xff));
}

// A chunk is length, type, data, and the CRC-32 of type + data (PNG spec section 5.3).
void put_chunk(std::string& out, const char type[4], const std::string& data) {
  put_u32(out, static_cast<std::uint32_t>(data.size()));
  const std::size_t type_at = out.size();
  out.append(type, 4);
  out += data;
  uLong crc = crc32(0L, Z_NULL, 0);
  crc = crc32(crc, reinterpret_cast<const Bytef*>(out.data() + type_at),
              static_cast<uInt>(4 + data.size()));
  put_u32(out, static_cast<std::uint32_t>(crc));
}

// Scanlines with a leading filter byte: filter 2 ("Up") stores each byte minus the byte above.
std::string filtered_scanlines(const RgbImage& image) {
  const std::size_t row_bytes = static_cast<std::size_t>(image.width) * 3;
  std::string raw(static_cast<std::size_t>(image.height) * (row_bytes + 1), '\0');
  for (int y = 0; y < image.height; ++y) {
    char* out = raw.data() + static_cast<std::size_t>(y) * (row_bytes + 1);
    const std::uint8_t* row = image.rgb.data() + image.offset(0, y);
    out[0] = 2;
    if (y == 0) {
      std::copy(row, row + row_bytes, out + 1);
      continue;
    }
    const std::uint8_t* above = row - row_bytes;
    for (std::size_t i = 0; i < row_bytes; ++i)
      out[i + 1] = static_cast<char>(static_cast<std::uint8_t>(row[i] - above[i]));
  }
  return raw;
}

}  // namespace

RgbImage RgbImage::filled(int width, int height, Rgb fill) {
  RgbImage image;
  image.width = std::max(width, 0);
  image.height = std::max(height, 0);
  image.rgb.resize(static_cast<std::size_t>(image.width) * static_cast<std::size_t>(image.height) *
                   3);
  for (std::size_t i = 0; i < image.rgb.size(); i += 3) {
    image.rgb[i] = fill[0];
    image.rgb[i + 1] = fill[1];
    image.rgb[i + 2] = fill[2];
  }
  return image;
}

analysis::Expected<std::string> encode_png(const RgbImage& image, const PngSettings& settings) {
  if (image.width <= 0 || image.height <= 0)
    return analysis::fail("encode_png: empty image (" + std::to_string(image.width) + " x " +
                          std::to_string(image.height) + ")");
  const std::size_t expected =
      static_cast<std::size_t>(image.width) * static_cast<std::size_t>(image.height) * 3;
  if (image.rgb.size() != expected)
    return analysis::fail("encode_png: pixel buffer holds " + std::to_string(image.rgb.size()) +
                          " bytes, width x height x 3 is " + std::to_string(expected));
  const std::string raw = filtered_scanlines(image);
  uLongf packed_size = compressBound(static_cast<uLong>(raw.size()));
  std::string packed(packed_size, '\0');
  const int level = std::clamp(settings.compression_level, 0, 9);
  const int status =
      compress2(reinterpret_cast<Bytef*>(packed.data()), &packed_size,
                reinterpret_cast<const Bytef*>(raw.data()), static_cast<uLong>(raw.size()), level);
  if (status != Z_OK)
    return analysis::fail("encode_png: zlib compress2 failed, status " + std::to_string(status));
  packed.resize(packed_size);

  std::string png("\x89PNG\r\n\x1a\n", 8);
  std::string header;
  put_u32(header, static_cast<std::uint32_t>(image.width));
  put_u32(header, static_cast<std::uint32_t>(image.height));
  header +=
      std::string("\x08\x02\x00\x00\x00", 5);  // depth 8, truecolour, deflate, 0, no interlace
  put_chunk(png, "IHDR", header);
  put_chunk(png, "IDAT", packed);
  put_chunk(png, "IEND", "");
  return png;
}

}  // namespace springscan::report
