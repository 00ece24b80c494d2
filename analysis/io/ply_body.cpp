#include "analysis/io/ply_body.hpp"

#include <bit>
#include <cmath>
#include <cstdio>
#include <cstring>

namespace springscan::analysis::io_detail {
namespace {

// One binary value of `type` at p, converted to double (exact for every PLY type).
template <typename T, typename U>
double load_as(const char* p, bool swap) {
  U raw;
  std::memcpy(&raw, p, sizeof raw);
  if constexpr (sizeof(U) == 2) {
    if (swap) raw = __builtin_bswap16(raw);
  } else if constexpr (sizeof(U) == 4) {
    if (swap) raw = __builtin_bswap32(raw);
  } else if constexpr (sizeof(U) == 8) {
    if (swap) raw = __builtin_bswap64(raw);
  }
  return static_cast<double>(std::bit_cast<T>(raw));
}

inline double load(const char* p, PlyType type, bool swap) {
  switch (type) {
    case PlyType::kInt8:
      return load_as<std::int8_t, std::uint8_t>(p, swap);
    case PlyType::kUint8:
      return load_as<std::uint8_t, std::uint8_t>(p, swap);
    case PlyType::kInt16:
      return load_as<std::int16_t, std::uint16_t>(p, swap);
    case PlyType::kUint16:
      return load_as<std::uint16_t, std::uint16_t>(p, swap);
    case PlyType::kInt32:
      return load_as<std::int32_t, std::uint32_t>(p, swap);
    case PlyType::kUint32:
      return load_as<std::uint32_t, std::uint32_t>(p, swap);
    case PlyType::kFloat32:
      return load_as<float, std::uint32_t>(p, swap);
    case PlyType::kFloat64:
      return load_as<double, std::uint64_t>(p, swap);
  }
  return 0.0;
}

// Colour channels: integer types are 0..255, float types 0..1 (as Open3D and MeshLab write them).
std::uint8_t to_channel(double v, PlyType type) {
  if (ply_type_is_float(type)) v *= 255.0;
  if (!(v > 0.0)) return 0;  // also NaN
  if (v >= 255.0) return 255;
  return static_cast<std::uint8_t>(std::lround(v));
}

// Face ids outside int32 (or NaN) become -1, "unknown face".
std::int32_t to_face_id(double v) {
  if (!(v >= -2147483648.0 && v <= 2147483647.0)) return -1;
  return static_cast<std::int32_t>(v);
}

inline void store(PointCloud& cloud, Target target, std::size_t i, double v, PlyType type) {
  switch (target) {
    case Target::kX:
      cloud.points[i].x() = v;
      break;
    case Target::kY:
      cloud.points[i].y() = v;
      break;
    case Target::kZ:
      cloud.points[i].z() = v;
      break;
    case Target::kNx:
      cloud.normals[i].x() = v;
      break;
    case Target::kNy:
      cloud.normals[i].y() = v;
      break;
    case Target::kNz:
      cloud.normals[i].z() = v;
      break;
    case Target::kRed:
      cloud.colors[i][0] = to_channel(v, type);
      break;
    case Target::kGreen:
      cloud.colors[i][1] = to_channel(v, type);
      break;
    case Target::kBlue:
      cloud.colors[i][2] = to_channel(v, type);
      break;
    case Target::kScalar:
      cloud.scalars[i] = v;
      break;
    case Target::kFaceId:
      cloud.face_ids[i] = to_face_id(v);
      break;
    case Target::kSkip:
    case Target::kCount:
      break;
  }
}

constexpr bool kLittleEndianHost = std::endian::native == std::endian::little;

}  // namespace

PlyBody::PlyBody(std::string_view bytes, const PlyHeader& header, const std::string& name)
    : bytes_(bytes),
      name_(name),
      format_(header.format),
      swap_((header.format == PlyBodyFormat::kBinaryBigEndian) == kLittleEndianHost),
      offset_(header.body_offset),
      cursor_(bytes.substr(header.body_offset), header.body_line) {}

Error PlyBody::error_at(const PlyElement& element, std::uint64_t record,
                        const std::string& what) const {
  const std::string where = format_ == PlyBodyFormat::kAscii
                                ? "line " + std::to_string(cursor_.line())
                                : "byte offset " + std::to_string(offset_);
  return fail(ErrorCode::kCorruption, name_ + ": " + where + ": PLY element '" + element.name +
                                          "' record " + std::to_string(record) + ": " + what);
}

std::optional<Error> PlyBody::check_fits(const PlyElement& element) const {
  if (element.count == 0) return std::nullopt;
  const std::string declared = name_ + ": PLY element '" + element.name + "' (header line " +
                               std::to_string(element.header_line) + ") declares " +
                               std::to_string(element.count) + " records";
  if (element.properties.empty())
    return fail(ErrorCode::kCorruption, declared + " but no properties");
  if (format_ == PlyBodyFormat::kAscii) {
    // Each value is at least one character and one separator (the last may lack the separator).
    const std::uint64_t min_bytes = 2 * element.properties.size();
    if (element.count > (cursor_.remaining() + 1) / min_bytes) {
      return fail(ErrorCode::kCorruption,
                  declared + " of at least " + std::to_string(element.properties.size()) +
                      " values but only " + std::to_string(cursor_.remaining()) +
                      " bytes remain (line " + std::to_string(cursor_.line()) + ")");
    }
    return std::nullopt;
  }
  const std::size_t record_size = element.min_record_size();
  const std::size_t remaining = bytes_.size() - offset_;
  if (element.count > remaining / record_size) {
    return fail(ErrorCode::kCorruption, declared + " of at least " + std::to_string(record_size) +
                                            " bytes but only " + std::to_string(remaining) +
                                            " bytes remain after byte offset " +
                                            std::to_string(offset_));
  }
  return std::nullopt;
}

std::optional<Error> PlyBody::binary_value(PlyType type, const PlyElement& element,
                                           std::uint64_t record, double& value) {
  const std::size_t size = ply_type_size(type);
  if (bytes_.size() - offset_ < size) return error_at(element, record, "file ends mid-record");
  value = load(bytes_.data() + offset_, type, swap_);
  offset_ += size;
  return std::nullopt;
}

std::optional<Error> PlyBody::ascii_value(const PlyElement& element, std::uint64_t record,
                                          double& value) {
  const std::string_view token = cursor_.next();
  if (token.empty()) return error_at(element, record, "file ends mid-record");
  const auto parsed = parse_double(token);
  if (!parsed) return error_at(element, record, "expected a number, got " + quoted(token));
  value = *parsed;
  return std::nullopt;
}

template <typename OnValue, typename OnItem>
std::optional<Error> PlyBody::walk_record(const PlyElement& element, std::uint64_t record,
                                          OnValue&& on_value, OnItem&& on_item) {
  const bool ascii = format_ == PlyBodyFormat::kAscii;
  const auto next = [&](PlyType type, double& v) {
    return ascii ? ascii_value(element, record, v) : binary_value(type, element, record, v);
  };
  for (std::size_t p = 0; p < element.properties.size(); ++p) {
    const auto& property = element.properties[p];
    double v = 0.0;
    if (!property.is_list) {
      if (auto error = next(property.type, v)) return error;
      on_value(p, v, property.type);
      continue;
    }
    if (auto error = next(property.count_type, v)) return error;
    if (!(v >= 0.0) || v != std::floor(v)) {
      return error_at(element, record, "list count " + std::to_string(v) + " is not a count");
    }
    // A count the rest of the file cannot hold is rejected before any item is read.
    const std::size_t item_size = ascii ? 2 : ply_type_size(property.type);
    const double available = ascii ? static_cast<double>(cursor_.remaining() + 1)
                                   : static_cast<double>(bytes_.size() - offset_);
    if (v * static_cast<double>(item_size) > available) {
      // %.15g: a count may be far beyond any integer type (1e57 from a double count field).
      char count_text[32];
      std::snprintf(count_text, sizeof count_text, "%.15g", v);
      return error_at(element, record,
                      std::string("list of ") + count_text + " items overruns the file");
    }
    const auto count = static_cast<std::uint64_t>(v);
    for (std::uint64_t k = 0; k < count; ++k) {
      if (auto error = next(property.type, v)) return error;
      if (auto error = on_item(p, k, v)) return error;
    }
  }
  return std::nullopt;
}

std::optional<Error> PlyBody::read_vertices_fixed(const PlyElement& element,
                                                  const VertexLayout& layout, PointCloud& cloud) {
  struct Slot {
    std::size_t offset;
    Target target;
    PlyType type;
  };
  std::vector<Slot> slots;
  std::size_t offset = 0;
  for (std::size_t p = 0; p < layout.targets.size(); ++p) {
    if (layout.targets[p] != Target::kSkip)
      slots.push_back({offset, layout.targets[p], layout.types[p]});
    offset += ply_type_size(layout.types[p]);
  }
  // check_fits proved count * record_size <= remaining, so no per-value bounds check is needed.
  const std::size_t record_size = offset;
  const auto count = static_cast<std::size_t>(element.count);
  const char* base = bytes_.data() + offset_;
  for (std::size_t i = 0; i < count; ++i) {
    const char* record = base + i * record_size;
    for (const Slot& slot : slots) {
      store(cloud, slot.target, i, load(record + slot.offset, slot.type, swap_), slot.type);
    }
  }
  offset_ += count * record_size;
  return std::nullopt;
}

std::optional<Error> PlyBody::read_vertices(const PlyElement& element, const VertexLayout& layout,
                                            PointCloud& cloud) {
  if (format_ != PlyBodyFormat::kAscii && !element.has_lists()) {
    return read_vertices_fixed(element, layout, cloud);
  }
  for (std::uint64_t i = 0; i < element.count; ++i) {
    const auto on_value = [&](std::size_t p, double v, PlyType type) {
      store(cloud, layout.targets[p], static_cast<std::size_t>(i), v, type);
    };
    const auto on_item = [](std::size_t, std::uint64_t, double) -> std::optional<Error> {
      return std::nullopt;
    };
    if (auto error = walk_record(element, i, on_value, on_item)) return error;
  }
  return std::nullopt;
}

std::optional<Error> PlyBody::read_faces(const PlyElement& element, std::size_t list,
                                         std::vector<std::array<std::uint32_t, 3>>& triangles) {
  triangles.reserve(triangles.size() + static_cast<std::size_t>(element.count));
  for (std::uint64_t f = 0; f < element.count; ++f) {
    std::uint32_t first = 0, previous = 0;
    std::uint64_t corners = 0;
    const auto on_value = [](std::size_t, double, PlyType) {};
    // Fan triangulation of the polygon (Turk's faces are convex polygons).
    const auto on_item = [&](std::size_t p, std::uint64_t k, double v) -> std::optional<Error> {
      if (p != list) return std::nullopt;
      if (!(v >= 0.0 && v < 4294967296.0) || v != std::floor(v)) {
        return error_at(element, f, "vertex index " + std::to_string(v) + " is invalid");
      }
      const auto index = static_cast<std::uint32_t>(v);
      if (k == 0) first = index;
      if (k >= 2) triangles.push_back({first, previous, index});
      previous = index;
      corners = k + 1;
      return std::nullopt;
    };
    if (auto error = walk_record(element, f, on_value, on_item)) return error;
    if (corners < 3) {
      return error_at(element, f, "face has " + std::to_string(corners) + " vertices, needs 3");
    }
  }
  return std::nullopt;
}

std::optional<Error> PlyBody::skip(const PlyElement& element) {
  if (format_ != PlyBodyFormat::kAscii && !element.has_lists()) {
    offset_ += static_cast<std::size_t>(element.count) * element.min_record_size();
    return std::nullopt;
  }
  const auto on_value = [](std::size_t, double, PlyType) {};
  const auto on_item = [](std::size_t, std::uint64_t, double) -> std::optional<Error> {
    return std::nullopt;
  };
  for (std::uint64_t i = 0; i < element.count; ++i) {
    if (auto error = walk_record(element, i, on_value, on_item)) return error;
  }
  return std::nullopt;
}

}  // namespace springscan::analysis::io_detail
