#pragma once
// Internal to ply_read.cpp and ply_write.cpp: the PLY header model and its parser.
// Format reference: Greg Turk, "The PLY Polygon File Format" (1994), and the property type
// aliases (int8 ... float64) that later writers such as VTK and Open3D use.

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "analysis/core/expected.hpp"

namespace springscan::analysis::io_detail {

enum class PlyType { kInt8, kUint8, kInt16, kUint16, kInt32, kUint32, kFloat32, kFloat64 };

enum class PlyBodyFormat { kAscii, kBinaryLittleEndian, kBinaryBigEndian };

/// char/uchar/short/ushort/int/uint/float/double and int8/uint8/.../float32/float64.
std::optional<PlyType> ply_type_from_name(std::string_view name);
/// The canonical name the writer uses (Turk's: "uchar", "int", "float", "double", ...).
const char* ply_type_name(PlyType type);
std::size_t ply_type_size(PlyType type);
bool ply_type_is_float(PlyType type);

struct PlyProperty {
  std::string name;
  PlyType type = PlyType::kFloat32;  ///< the value type (the item type for a list)
  bool is_list = false;
  PlyType count_type = PlyType::kUint8;  ///< lists only: the type of the leading count
};

struct PlyElement {
  std::string name;
  std::uint64_t count = 0;
  std::vector<PlyProperty> properties;
  std::size_t header_line = 0;  ///< where the element was declared, for messages

  bool has_lists() const;
  /// Bytes of one binary record: exact without lists, the minimum (all lists empty) with them.
  std::size_t min_record_size() const;
};

struct PlyHeader {
  PlyBodyFormat format = PlyBodyFormat::kAscii;
  std::vector<PlyElement> elements;
  std::size_t body_offset = 0;  ///< first byte after the end_header line
  std::size_t body_line = 0;    ///< 1-based line number of the first body line (ascii)
};

/// Parses the header; errors name `name` and the header line.
Expected<PlyHeader> parse_ply_header(std::string_view bytes, const std::string& name);

}  // namespace springscan::analysis::io_detail
