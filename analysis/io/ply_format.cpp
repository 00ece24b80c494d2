#include "analysis/io/ply_format.hpp"

#include <array>

#include "analysis/io/io_text.hpp"

namespace springscan::analysis::io_detail {
namespace {

struct TypeInfo {
  PlyType type;
  const char* name;
  const char* alias;
  std::size_t size;
};

constexpr std::array<TypeInfo, 8> kTypes = {{
    {PlyType::kInt8, "char", "int8", 1},
    {PlyType::kUint8, "uchar", "uint8", 1},
    {PlyType::kInt16, "short", "int16", 2},
    {PlyType::kUint16, "ushort", "uint16", 2},
    {PlyType::kInt32, "int", "int32", 4},
    {PlyType::kUint32, "uint", "uint32", 4},
    {PlyType::kFloat32, "float", "float32", 4},
    {PlyType::kFloat64, "double", "float64", 8},
}};

const TypeInfo& info(PlyType type) { return kTypes[static_cast<std::size_t>(type)]; }

// Splits one header line into its whitespace-separated words.
std::vector<std::string_view> words(std::string_view line) {
  std::vector<std::string_view> out;
  TextCursor cursor(line, 1);
  for (auto w = cursor.next(); !w.empty(); w = cursor.next()) out.push_back(w);
  return out;
}

// One parsed line of the header; the state it changes lives in `header`.
struct HeaderLineParser {
  const std::string& name;
  PlyHeader& header;
  bool saw_format = false;

  Error error(std::size_t line, const std::string& what) const {
    return fail(ErrorCode::kCorruption,
                name + ": PLY header line " + std::to_string(line) + ": " + what);
  }

  std::optional<Error> format(const std::vector<std::string_view>& w, std::size_t line) {
    if (w.size() != 3) return error(line, "expected 'format ENCODING 1.0'");
    if (w[1] == "ascii")
      header.format = PlyBodyFormat::kAscii;
    else if (w[1] == "binary_little_endian")
      header.format = PlyBodyFormat::kBinaryLittleEndian;
    else if (w[1] == "binary_big_endian")
      header.format = PlyBodyFormat::kBinaryBigEndian;
    else
      return error(line, "unknown format " + quoted(w[1]));
    if (w[2] != "1.0") return error(line, "unsupported version " + quoted(w[2]));
    saw_format = true;
    return std::nullopt;
  }

  std::optional<Error> element(const std::vector<std::string_view>& w, std::size_t line) {
    if (w.size() != 3) return error(line, "expected 'element NAME COUNT'");
    const auto count = parse_count(w[2]);
    if (!count) return error(line, "element count " + quoted(w[2]) + " is not a number");
    header.elements.push_back(PlyElement{std::string(w[1]), *count, {}, line});
    return std::nullopt;
  }

  std::optional<Error> property(const std::vector<std::string_view>& w, std::size_t line) {
    if (header.elements.empty()) return error(line, "property before any element");
    PlyProperty property;
    if (w.size() == 5 && w[1] == "list") {
      const auto count_type = ply_type_from_name(w[2]);
      const auto item_type = ply_type_from_name(w[3]);
      if (!count_type) return error(line, "unknown list count type " + quoted(w[2]));
      if (!item_type) return error(line, "unknown list item type " + quoted(w[3]));
      if (ply_type_is_float(*count_type)) return error(line, "list count type is not integer");
      property = PlyProperty{std::string(w[4]), *item_type, true, *count_type};
    } else if (w.size() == 3) {
      const auto type = ply_type_from_name(w[1]);
      if (!type) return error(line, "unknown property type " + quoted(w[1]));
      property = PlyProperty{std::string(w[2]), *type, false, PlyType::kUint8};
    } else {
      return error(line, "expected 'property TYPE NAME' or 'property list COUNT ITEM NAME'");
    }
    header.elements.back().properties.push_back(std::move(property));
    return std::nullopt;
  }

  std::optional<Error> parse(std::string_view text, std::size_t line) {
    const auto w = words(text);
    if (w.empty() || w[0] == "comment" || w[0] == "obj_info") return std::nullopt;
    if (w[0] == "format") return format(w, line);
    if (!saw_format) return error(line, "expected the format line, got " + quoted(w[0]));
    if (w[0] == "element") return element(w, line);
    if (w[0] == "property") return property(w, line);
    return error(line, "unknown keyword " + quoted(w[0]));
  }
};

}  // namespace

std::optional<PlyType> ply_type_from_name(std::string_view name) {
  for (const auto& t : kTypes) {
    if (name == t.name || name == t.alias) return t.type;
  }
  return std::nullopt;
}

const char* ply_type_name(PlyType type) { return info(type).name; }
std::size_t ply_type_size(PlyType type) { return info(type).size; }
bool ply_type_is_float(PlyType type) {
  return type == PlyType::kFloat32 || type == PlyType::kFloat64;
}

bool PlyElement::has_lists() const {
  for (const auto& p : properties) {
    if (p.is_list) return true;
  }
  return false;
}

std::size_t PlyElement::min_record_size() const {
  std::size_t size = 0;
  for (const auto& p : properties) size += ply_type_size(p.is_list ? p.count_type : p.type);
  return size;
}

Expected<PlyHeader> parse_ply_header(std::string_view bytes, const std::string& name) {
  PlyHeader header;
  HeaderLineParser parser{name, header};
  if (!bytes.starts_with("ply\n") && !bytes.starts_with("ply\r\n")) {
    return fail(ErrorCode::kCorruption,
                name + ": not a PLY file (it does not start with a 'ply' line)");
  }
  std::size_t pos = bytes.find('\n') + 1;
  for (std::size_t line = 2;; ++line) {
    const std::size_t eol = bytes.find('\n', pos);
    if (eol == std::string_view::npos) {
      return fail(ErrorCode::kCorruption, name + ": PLY header has no end_header line (read " +
                                              std::to_string(line - 1) + " lines)");
    }
    std::string_view text = bytes.substr(pos, eol - pos);
    if (!text.empty() && text.back() == '\r') text.remove_suffix(1);
    pos = eol + 1;
    if (text == "end_header") {
      if (!parser.saw_format) return parser.error(line, "end_header before the format line");
      header.body_offset = pos;
      header.body_line = line + 1;
      return header;
    }
    if (auto error = parser.parse(text, line)) return *error;
  }
}

}  // namespace springscan::analysis::io_detail
