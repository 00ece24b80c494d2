// STL, ascii and binary. Binary: an 80-byte header, a little-endian uint32 triangle count n,
// then n records of 50 bytes (normal, three corners as float32, a uint16 attribute). Many
// binary files start their header with "solid" too, so the size 84 + 50 n decides first.
// Corners are merged into unique vertices by exact value, in order of first appearance.
#include <bit>
#include <cstring>
#include <unordered_map>

#include "analysis/io/io_text.hpp"
#include "analysis/io/point_io.hpp"

namespace springscan::analysis {
namespace {

using io_detail::parse_double;
using io_detail::quoted;
using io_detail::TextCursor;

constexpr std::size_t kHeaderBytes = 84;
constexpr std::size_t kRecordBytes = 50;

std::uint32_t load_u32_le(const char* p) {
  std::uint32_t v;
  std::memcpy(&v, p, 4);
  if constexpr (std::endian::native == std::endian::big) v = __builtin_bswap32(v);
  return v;
}

float load_f32_le(const char* p) { return std::bit_cast<float>(load_u32_le(p)); }

// Merges corners with identical coordinates into one vertex.
class Welder {
 public:
  explicit Welder(std::size_t triangles) { index_.reserve(triangles); }

  std::uint32_t add(const Vec3& p) {
    const Vec3 q = p + Vec3::Zero();  // -0.0 + 0.0 == +0.0: both zeros weld together
    const Key key{std::bit_cast<std::uint64_t>(q.x()), std::bit_cast<std::uint64_t>(q.y()),
                  std::bit_cast<std::uint64_t>(q.z())};
    const auto [it, inserted] =
        index_.try_emplace(key, static_cast<std::uint32_t>(surface_.cloud.points.size()));
    if (inserted) surface_.cloud.points.push_back(q);
    return it->second;
  }
  Surface& surface() { return surface_; }

 private:
  using Key = std::array<std::uint64_t, 3>;
  struct KeyHash {
    std::size_t operator()(const Key& k) const {
      std::uint64_t h = k[0] * 0x9E3779B97F4A7C15ull;
      h = (h ^ (h >> 29) ^ k[1]) * 0xBF58476D1CE4E5B9ull;
      h = (h ^ (h >> 32) ^ k[2]) * 0x94D049BB133111EBull;
      return static_cast<std::size_t>(h ^ (h >> 31));
    }
  };
  std::unordered_map<Key, std::uint32_t, KeyHash> index_;
  Surface surface_;
};

Expected<Surface> parse_binary(std::string_view bytes, std::uint64_t count,
                               const std::string& name) {
  Welder welder(static_cast<std::size_t>(count));
  auto& triangles = welder.surface().triangles;
  triangles.reserve(static_cast<std::size_t>(count));
  for (std::size_t t = 0; t < count; ++t) {
    const char* record = bytes.data() + kHeaderBytes + t * kRecordBytes;
    std::array<std::uint32_t, 3> triangle{};
    for (int c = 0; c < 3; ++c) {
      const char* p = record + 12 + 12 * c;  // skip the stored normal: we recompute normals
      const Vec3 corner(load_f32_le(p), load_f32_le(p + 4), load_f32_le(p + 8));
      if (!corner.allFinite()) {
        return fail(ErrorCode::kCorruption,
                    name + ": byte offset " + std::to_string(p - bytes.data()) + ": triangle " +
                        std::to_string(t) + " has a non-finite corner (NaN or Inf)");
      }
      triangle[c] = welder.add(corner);
    }
    triangles.push_back(triangle);
  }
  return std::move(welder.surface());
}

// "facet normal a b c outer loop vertex x y z (x3) endloop endfacet", repeated, in "solid NAME"
// ... "endsolid NAME" blocks.
class AsciiStlParser {
 public:
  AsciiStlParser(std::string_view text, const std::string& name) : cursor_(text, 1), name_(name) {}

  Expected<Surface> parse() {
    if (cursor_.next() != "solid") return error("ascii STL does not start with 'solid'");
    skip_line();
    for (;;) {
      const std::string_view token = cursor_.next();
      if (token == "endsolid") {
        skip_line();
        const std::string_view more = cursor_.next();
        if (more.empty()) break;
        if (more != "solid") return error("expected 'solid' or the end, got " + quoted(more));
        skip_line();
      } else if (token == "facet") {
        if (auto e = facet()) return *e;
      } else {
        return error(token.empty() ? "file ends before 'endsolid'"
                                   : "expected 'facet' or 'endsolid', got " + quoted(token));
      }
    }
    return std::move(welder_.surface());
  }

 private:
  std::optional<Error> facet() {
    double ignored = 0.0;
    if (auto e = expect("normal")) return e;
    for (int k = 0; k < 3; ++k) {
      if (auto e = number(ignored)) return e;
    }
    if (auto e = expect("outer")) return e;
    if (auto e = expect("loop")) return e;
    std::array<std::uint32_t, 3> triangle{};
    const std::size_t index = welder_.surface().triangles.size();
    for (auto& corner : triangle) {
      if (auto e = expect("vertex")) return e;
      Vec3 p;
      for (int k = 0; k < 3; ++k) {
        if (auto e = number(p[k])) return e;
      }
      if (!p.allFinite()) {
        return error("triangle " + std::to_string(index) + " has a non-finite corner (NaN or Inf)");
      }
      corner = welder_.add(p);
    }
    if (auto e = expect("endloop")) return e;
    if (auto e = expect("endfacet")) return e;
    welder_.surface().triangles.push_back(triangle);
    return std::nullopt;
  }

  std::optional<Error> expect(std::string_view word) {
    const std::string_view token = cursor_.next();
    if (token == word) return std::nullopt;
    return error("expected '" + std::string(word) + "', got " +
                 (token.empty() ? std::string("the end of the file") : quoted(token)));
  }

  std::optional<Error> number(double& value) {
    const std::string_view token = cursor_.next();
    const auto parsed = parse_double(token);
    if (!parsed) return error("expected a number, got " + quoted(token));
    value = *parsed;
    return std::nullopt;
  }

  // The rest of a "solid NAME" line is a free-form name.
  void skip_line() {
    TextCursor probe = cursor_;
    const std::size_t line = cursor_.line();
    for (TextCursor ahead = cursor_; !ahead.next().empty() && ahead.line() == line;) {
      probe = ahead;
    }
    cursor_ = probe;
  }

  Error error(const std::string& what) const {
    return fail(ErrorCode::kCorruption,
                name_ + ": line " + std::to_string(cursor_.line()) + ": " + what);
  }

  TextCursor cursor_;
  const std::string& name_;
  Welder welder_{0};
};

bool starts_with_solid(std::string_view bytes) {
  std::size_t i = 0;
  while (i < bytes.size() && TextCursor::is_space(bytes[i])) ++i;
  return bytes.substr(i).starts_with("solid");
}

}  // namespace

Expected<Surface> parse_stl(std::string_view bytes, const std::string& name) {
  if (bytes.empty()) return fail(ErrorCode::kCorruption, name + ": empty file");
  if (bytes.size() >= kHeaderBytes) {
    const std::uint64_t count = load_u32_le(bytes.data() + 80);
    const std::uint64_t needed = kHeaderBytes + kRecordBytes * count;
    if (needed == bytes.size()) return parse_binary(bytes, count, name);
    if (!starts_with_solid(bytes)) {
      if (needed > bytes.size()) {
        return fail(ErrorCode::kCorruption,
                    name + ": binary STL declares " + std::to_string(count) + " triangles (needs " +
                        std::to_string(needed) + " bytes) but the file has " +
                        std::to_string(bytes.size()) + " bytes");
      }
      return parse_binary(bytes, count, name);  // trailing bytes after the records are ignored
    }
  } else if (!starts_with_solid(bytes)) {
    return fail(ErrorCode::kCorruption, name + ": not an STL file (" +
                                            std::to_string(bytes.size()) +
                                            " bytes: too short for binary, and no 'solid')");
  }
  return AsciiStlParser(bytes, name).parse();
}

Expected<std::string> format_stl(const Surface& surface) {
  const auto& points = surface.cloud.points;
  if (surface.triangles.empty()) return fail("cannot write STL: the surface has no triangles");
  if (surface.triangles.size() > 0xFFFFFFFFu) return fail("cannot write STL: too many triangles");
  std::string out(kHeaderBytes + kRecordBytes * surface.triangles.size(), '\0');
  const std::string title = "binary STL written by springscan; mm";  // must not start "solid"
  std::memcpy(out.data(), title.data(), title.size());
  char* p = out.data() + 80;
  const auto put_u32 = [&p](std::uint32_t v) {
    if constexpr (std::endian::native == std::endian::big) v = __builtin_bswap32(v);
    std::memcpy(p, &v, 4);
    p += 4;
  };
  const auto put_vec = [&](const Vec3& v) {
    for (int k = 0; k < 3; ++k) put_u32(std::bit_cast<std::uint32_t>(static_cast<float>(v[k])));
  };
  put_u32(static_cast<std::uint32_t>(surface.triangles.size()));
  for (std::size_t t = 0; t < surface.triangles.size(); ++t) {
    const auto& tri = surface.triangles[t];
    if (tri[0] >= points.size() || tri[1] >= points.size() || tri[2] >= points.size()) {
      return fail("cannot write STL: triangle " + std::to_string(t) + " refers to a vertex past " +
                  std::to_string(points.size()));
    }
    const Vec3& a = points[tri[0]];
    const Vec3 n = (points[tri[1]] - a).cross(points[tri[2]] - a);
    put_vec(n.norm() > 0.0 ? Vec3(n.normalized()) : Vec3::Zero());
    for (auto index : tri) put_vec(points[index]);
    p += 2;  // attribute byte count: zero
  }
  return out;
}

}  // namespace springscan::analysis
