// PLY writer: one vertex element with every attribute the cloud has, and a face element when
// the surface has triangles (Turk's "property list uchar int vertex_indices").
#include <bit>
#include <charconv>
#include <cstring>

#include "analysis/io/ply_format.hpp"
#include "analysis/io/point_io.hpp"

namespace springscan::analysis {
namespace {

using io_detail::PlyType;

constexpr bool kLittleEndianHost = std::endian::native == std::endian::little;

// Appends values in one encoding; binary values are byte-swapped when the file's byte order
// is not the host's.
class Sink {
 public:
  Sink(PlyEncoding encoding, std::string& out)
      : ascii_(encoding == PlyEncoding::kAscii),
        swap_((encoding == PlyEncoding::kBinaryBigEndian) == kLittleEndianHost),
        out_(out) {}

  void put(double v, PlyType type) {
    switch (type) {
      case PlyType::kFloat64:
        return put_as<double, std::uint64_t>(v);
      case PlyType::kFloat32:
        return put_as<float, std::uint32_t>(static_cast<float>(v));
      case PlyType::kInt32:
        return put_as<std::int32_t, std::uint32_t>(static_cast<std::int32_t>(v));
      case PlyType::kUint8:
        return put_as<std::uint8_t, std::uint8_t>(static_cast<std::uint8_t>(v));
      default:
        return;  // the writer uses only the four types above
    }
  }
  void end_record() {
    if (ascii_) out_.back() = '\n';
  }

 private:
  template <typename T, typename U>
  void put_as(T v) {
    if (ascii_) {
      char text[32];
      const auto [end, ec] = std::to_chars(text, text + sizeof text, v);  // shortest exact form
      out_.append(text, end);
      out_ += ' ';
      return;
    }
    auto raw = std::bit_cast<U>(v);
    if constexpr (sizeof(U) == 2) {
      if (swap_) raw = __builtin_bswap16(raw);
    } else if constexpr (sizeof(U) == 4) {
      if (swap_) raw = __builtin_bswap32(raw);
    } else if constexpr (sizeof(U) == 8) {
      if (swap_) raw = __builtin_bswap64(raw);
    }
    char bytes[sizeof raw];
    std::memcpy(bytes, &raw, sizeof raw);
    out_.append(bytes, sizeof raw);
  }

  bool ascii_;
  bool swap_;
  std::string& out_;
};

const char* encoding_name(PlyEncoding encoding) {
  switch (encoding) {
    case PlyEncoding::kAscii:
      return "ascii";
    case PlyEncoding::kBinaryBigEndian:
      return "binary_big_endian";
    case PlyEncoding::kBinaryLittleEndian:
      return "binary_little_endian";
  }
  return "binary_little_endian";
}

std::string header(const Surface& surface, const PointWriteOptions& options, PlyType real) {
  const PointCloud& cloud = surface.cloud;
  const std::string type = io_detail::ply_type_name(real);
  std::string h = "ply\nformat " + std::string(encoding_name(options.ply_encoding)) + " 1.0\n";
  h += "comment written by springscan; coordinates in mm\n";
  h += "element vertex " + std::to_string(cloud.size()) + "\n";
  for (const char* axis : {"x", "y", "z"}) h += "property " + type + " " + axis + "\n";
  if (cloud.has_normals()) {
    for (const char* axis : {"nx", "ny", "nz"}) h += "property " + type + " " + axis + "\n";
  }
  if (cloud.has_colors()) h += "property uchar red\nproperty uchar green\nproperty uchar blue\n";
  if (cloud.has_scalars()) h += "property " + type + " " + options.scalar_name + "\n";
  if (cloud.has_face_ids()) h += "property int face_id\n";
  if (!surface.triangles.empty()) {
    h += "element face " + std::to_string(surface.triangles.size()) + "\n";
    h += "property list uchar int vertex_indices\n";
  }
  return h + "end_header\n";
}

std::optional<Error> check_writable(const Surface& surface) {
  const PointCloud& cloud = surface.cloud;
  if (!cloud.attributes_consistent()) {
    return fail("cannot write a point cloud whose attributes do not have one entry per point");
  }
  const std::size_t n = cloud.size();
  if (!surface.triangles.empty() && n > 2147483647u) {
    return fail("cannot write " + std::to_string(n) + " vertices with int face indices");
  }
  for (std::size_t f = 0; f < surface.triangles.size(); ++f) {
    for (auto index : surface.triangles[f]) {
      if (index >= n) {
        return fail("triangle " + std::to_string(f) + " refers to vertex " + std::to_string(index) +
                    " of " + std::to_string(n));
      }
    }
  }
  return std::nullopt;
}

}  // namespace

Expected<std::string> format_ply(const Surface& surface, const PointWriteOptions& options) {
  if (auto error = check_writable(surface)) return *error;
  if (options.scalar_name.empty() ||
      options.scalar_name.find_first_of(" \t\r\n") != std::string::npos) {
    return fail("PLY scalar property name '" + options.scalar_name + "' is empty or has spaces");
  }
  const PlyType real = options.single_precision ? PlyType::kFloat32 : PlyType::kFloat64;
  const PointCloud& cloud = surface.cloud;
  std::string out = header(surface, options, real);
  const std::size_t per_point = 3 * (cloud.has_normals() ? 2 : 1) + (cloud.has_scalars() ? 1 : 0);
  out.reserve(out.size() + cloud.size() * (per_point * 8 + 8) + surface.triangles.size() * 13);
  Sink sink(options.ply_encoding, out);
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    for (int k = 0; k < 3; ++k) sink.put(cloud.points[i][k], real);
    if (cloud.has_normals()) {
      for (int k = 0; k < 3; ++k) sink.put(cloud.normals[i][k], real);
    }
    if (cloud.has_colors()) {
      for (auto channel : cloud.colors[i]) sink.put(channel, PlyType::kUint8);
    }
    if (cloud.has_scalars()) sink.put(cloud.scalars[i], real);
    if (cloud.has_face_ids()) sink.put(cloud.face_ids[i], PlyType::kInt32);
    sink.end_record();
  }
  for (const auto& triangle : surface.triangles) {
    sink.put(3, PlyType::kUint8);
    for (auto index : triangle) sink.put(index, PlyType::kInt32);
    sink.end_record();
  }
  return out;
}

}  // namespace springscan::analysis
