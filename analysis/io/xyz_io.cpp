// Column text files (.xyz .csv .txt .pts): one point per line, fields separated by spaces, tabs,
// commas or semicolons. Columns: 3 = x y z, 4 = x y z scalar, 6 = x y z nx ny nz,
// 7 = x y z nx ny nz scalar. Blank lines and comment lines (# or //) are skipped, and so is one
// header line of names and a PTS point-count line, both only before the first point.
#include <charconv>
#include <cmath>

#include "analysis/io/io_text.hpp"
#include "analysis/io/point_io.hpp"

namespace springscan::analysis {
namespace {

using io_detail::parse_double;
using io_detail::quoted;

bool is_separator(char c) { return c == ' ' || c == '\t' || c == ',' || c == ';' || c == '\r'; }

// Splits a line into at most 8 fields (one more than any valid row, to detect too many).
std::size_t split(std::string_view line, std::array<std::string_view, 8>& fields) {
  std::size_t n = 0, pos = 0;
  while (pos < line.size() && n < fields.size()) {
    while (pos < line.size() && is_separator(line[pos])) ++pos;
    const std::size_t begin = pos;
    while (pos < line.size() && !is_separator(line[pos])) ++pos;
    if (pos > begin) fields[n++] = line.substr(begin, pos - begin);
  }
  return n;
}

bool valid_column_count(std::size_t n) { return n == 3 || n == 4 || n == 6 || n == 7; }

class XyzParser {
 public:
  explicit XyzParser(const std::string& name) : name_(name) {}

  std::optional<Error> line(std::string_view text, std::size_t number) {
    std::size_t start = 0;
    while (start < text.size() && is_separator(text[start])) ++start;
    text.remove_prefix(start);
    if (text.empty() || text.front() == '#' || text.starts_with("//")) return std::nullopt;
    std::array<std::string_view, 8> fields;
    const std::size_t n = split(text, fields);
    std::array<double, 7> values{};
    for (std::size_t c = 0; c < n && c < values.size(); ++c) {
      const auto v = parse_double(fields[c]);
      if (!v) return non_number(number, c, fields[c]);
      values[c] = *v;
    }
    if (columns_ == 0 && n == 1) return std::nullopt;  // PTS: the point count line
    if (columns_ == 0) {
      if (!valid_column_count(n)) {
        return error(number, std::to_string(n) +
                                 " columns; expected 3 (x y z), 4 (+ scalar), "
                                 "6 (+ nx ny nz) or 7");
      }
      columns_ = n;
    } else if (n != columns_) {
      return error(number, std::to_string(n) + " columns where earlier lines have " +
                               std::to_string(columns_));
    }
    return add(values, number);
  }

  Surface finish() { return std::move(surface_); }

 private:
  std::optional<Error> non_number(std::size_t number, std::size_t column, std::string_view field) {
    // Before the first point, a line of words is a header of column names.
    if (columns_ == 0 && !header_seen_ && column == 0) {
      header_seen_ = true;
      return std::nullopt;
    }
    return error(number, "column " + std::to_string(column + 1) + ": expected a number, got " +
                             quoted(field));
  }

  std::optional<Error> add(const std::array<double, 7>& v, std::size_t number) {
    PointCloud& cloud = surface_.cloud;
    const Vec3 p(v[0], v[1], v[2]);
    if (!p.allFinite())
      return error(number, "point " + std::to_string(cloud.size()) +
                               " has a non-finite coordinate (NaN or Inf)");
    cloud.points.push_back(p);
    if (columns_ >= 6) {
      const Vec3 normal(v[3], v[4], v[5]);
      if (!normal.allFinite()) return error(number, "non-finite normal (NaN or Inf)");
      cloud.normals.push_back(normal);
    }
    if (columns_ == 4 || columns_ == 7) {
      const double s = v[columns_ - 1];
      if (!std::isfinite(s)) return error(number, "non-finite scalar (NaN or Inf)");
      cloud.scalars.push_back(s);
    }
    return std::nullopt;
  }

  Error error(std::size_t number, const std::string& what) const {
    return fail(ErrorCode::kCorruption, name_ + ": line " + std::to_string(number) + ": " + what);
  }

  const std::string& name_;
  Surface surface_;
  std::size_t columns_ = 0;
  bool header_seen_ = false;
};

}  // namespace

Expected<Surface> parse_xyz(std::string_view text, const std::string& name) {
  if (text.find('\0') != std::string_view::npos) {
    return fail(ErrorCode::kCorruption, name + ": byte offset " + std::to_string(text.find('\0')) +
                                            ": NUL byte in a text point file (binary data?)");
  }
  XyzParser parser(name);
  std::size_t number = 1;
  for (std::size_t pos = 0; pos < text.size(); ++number) {
    std::size_t eol = text.find('\n', pos);
    if (eol == std::string_view::npos) eol = text.size();
    if (auto error = parser.line(text.substr(pos, eol - pos), number)) return *error;
    pos = eol + 1;
  }
  Surface surface = parser.finish();
  if (surface.cloud.empty())
    return fail(ErrorCode::kCorruption, name + ": no points (empty file or only comments)");
  return surface;
}

Expected<std::string> format_xyz(const Surface& surface) {
  const PointCloud& cloud = surface.cloud;
  if (!cloud.attributes_consistent()) {
    return fail("cannot write a point cloud whose attributes do not have one entry per point");
  }
  std::string out = "# x y z";
  if (cloud.has_normals()) out += " nx ny nz";
  if (cloud.has_scalars()) out += " scalar";
  out += "  (mm; written by springscan)\n";
  char text[32];
  const auto put = [&](double v, char after) {
    const auto [end, ec] = std::to_chars(text, text + sizeof text, v);  // shortest exact form
    out.append(text, end);
    out += after;
  };
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const bool more = cloud.has_normals() || cloud.has_scalars();
    put(cloud.points[i].x(), ' ');
    put(cloud.points[i].y(), ' ');
    put(cloud.points[i].z(), more ? ' ' : '\n');
    if (cloud.has_normals()) {
      put(cloud.normals[i].x(), ' ');
      put(cloud.normals[i].y(), ' ');
      put(cloud.normals[i].z(), cloud.has_scalars() ? ' ' : '\n');
    }
    if (cloud.has_scalars()) put(cloud.scalars[i], '\n');
  }
  return out;
}

}  // namespace springscan::analysis
