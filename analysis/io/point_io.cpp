// Format dispatch by extension and the file-level entry points of point_io.hpp. The parsers
// and formatters live in ply_*.cpp, xyz_io.cpp and stl_io.cpp.
#include "analysis/io/point_io.hpp"

#include <filesystem>

#include "analysis/io/file_io.hpp"
#include "analysis/io/io_text.hpp"

namespace springscan::analysis {
namespace {

Error unknown_extension(const std::string& path) {
  return fail(path + ": unknown point file extension (expected .ply .xyz .csv .txt .pts .stl)");
}

TriangleMesh to_mesh(Surface surface) {
  TriangleMesh mesh;
  mesh.vertices = std::move(surface.cloud.points);
  mesh.triangles = std::move(surface.triangles);
  return mesh;
}

}  // namespace

std::optional<PointFormat> point_format_for_path(const std::string& path) {
  const std::string ext = io_detail::lower(std::filesystem::path(path).extension().string());
  if (ext == ".ply") return PointFormat::kPly;
  if (ext == ".xyz" || ext == ".csv" || ext == ".txt" || ext == ".pts") return PointFormat::kXyz;
  if (ext == ".stl") return PointFormat::kStl;
  return std::nullopt;
}

Expected<Surface> parse_surface(std::string_view bytes, PointFormat format, const std::string& name,
                                const PointReadOptions& options) {
  if (bytes.empty()) return fail(ErrorCode::kCorruption, name + ": empty file");
  switch (format) {
    case PointFormat::kPly:
      return parse_ply(bytes, name, options);
    case PointFormat::kXyz:
      return parse_xyz(bytes, name);
    case PointFormat::kStl:
      return parse_stl(bytes, name);
  }
  return fail(ErrorCode::kCorruption, name + ": unknown point format");
}

Expected<std::string> format_surface(const Surface& surface, PointFormat format,
                                     const PointWriteOptions& options) {
  switch (format) {
    case PointFormat::kPly:
      return format_ply(surface, options);
    case PointFormat::kXyz:
      return format_xyz(surface);
    case PointFormat::kStl:
      return format_stl(surface);
  }
  return fail(ErrorCode::kCorruption, "unknown point format");
}

Expected<Surface> read_surface(const std::string& path, const PointReadOptions& options) {
  const auto format = point_format_for_path(path);
  if (!format) return unknown_extension(path);
  auto bytes = read_file_bytes(path);
  if (!bytes) return bytes.error();
  return parse_surface(*bytes, *format, path, options);
}

Expected<PointCloud> read_point_cloud(const std::string& path, const PointReadOptions& options) {
  PointReadOptions points_only = options;
  points_only.read_faces = false;
  auto surface = read_surface(path, points_only);
  if (!surface) return surface.error();
  return std::move(surface->cloud);
}

Expected<TriangleMesh> read_mesh(const std::string& path) {
  auto surface = read_surface(path);
  if (!surface) return surface.error();
  if (surface->triangles.empty())
    return fail(ErrorCode::kCorruption, path + ": the file has no triangles");
  return to_mesh(std::move(*surface));
}

Expected<bool> write_surface(const std::string& path, const Surface& surface,
                             const PointWriteOptions& options) {
  const auto format = point_format_for_path(path);
  if (!format) return unknown_extension(path);
  auto bytes = format_surface(surface, *format, options);
  if (!bytes) return bytes.error().prepend(path + ": ");
  return write_file_atomically(path, *bytes);
}

Expected<bool> write_point_cloud(const std::string& path, const PointCloud& cloud,
                                 const PointWriteOptions& options) {
  Surface surface;
  surface.cloud = cloud;  // a copy; clouds are written rarely compared with how often they are read
  return write_surface(path, surface, options);
}

Expected<bool> write_mesh(const std::string& path, const TriangleMesh& mesh,
                          const PointWriteOptions& options) {
  Surface surface;
  surface.cloud.points = mesh.vertices;
  surface.triangles = mesh.triangles;
  return write_surface(path, surface, options);
}

}  // namespace springscan::analysis
