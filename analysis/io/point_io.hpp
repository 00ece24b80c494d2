#pragma once
// Reading and writing scans and meshes: PLY (ascii, binary little and big endian), XYZ/CSV/TXT/PTS
// columns, STL (ascii and binary). DESIGN.md pipeline stage 1 "Load".
//
// Every reader parses from memory (the file is read in one go) and treats the bytes as
// untrusted: counts in headers are checked against the bytes that remain before anything is
// reserved, and every error names the file and the line (text) or byte offset (binary).
// Coordinates, normals and scalars must be finite; a NaN or Inf is rejected with the vertex index.
// All functions are thread-safe (no shared state).

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "analysis/core/expected.hpp"
#include "analysis/core/point_cloud.hpp"

namespace springscan::analysis {

/// The file formats, chosen from the file name's extension (case-insensitive).
enum class PointFormat {
  kPly,  ///< .ply
  kXyz,  ///< .xyz .csv .txt .pts: whitespace- or comma-separated columns
  kStl,  ///< .stl
};

/// The format for `path` by its extension, or nullopt when the extension is not one we read.
std::optional<PointFormat> point_format_for_path(const std::string& path);

/// A point cloud with the triangles that connect its points, when the file has any (STL, PLY
/// faces). Triangle indices refer to `cloud.points`.
struct Surface {
  PointCloud cloud;                                     ///< points and their attributes
  std::vector<std::array<std::uint32_t, 3>> triangles;  ///< empty for plain point files
};

struct PointReadOptions {
  /// PLY vertex property read into PointCloud::scalars. Empty: the first vertex property named
  /// `scalar`, `scalar_*`, `signed_deviation_mm`, `deviation`, `quality` or `intensity`. A
  /// name given here that the file lacks is an error.
  std::string scalar_property = "";
  /// Read PLY face elements into Surface::triangles (otherwise they are skipped unparsed).
  bool read_faces = true;
};

/// PLY body encodings the writer produces.
enum class PlyEncoding {
  kBinaryLittleEndian,  ///< the default: compact and fast
  kAscii,               ///< human-readable; doubles printed in their shortest exact form
  kBinaryBigEndian,     ///< for old tools; also exercised by the tests
};

struct PointWriteOptions {
  /// PLY body encoding (XYZ is always text and STL always binary).
  PlyEncoding ply_encoding = PlyEncoding::kBinaryLittleEndian;
  /// Store PLY coordinates, normals and scalars as float (4 bytes) instead of double; loses
  /// precision below about 1e-4 mm at 1 m.
  bool single_precision = false;
  /// Name of the PLY vertex property that holds PointCloud::scalars.
  std::string scalar_name = "scalar";
};

// ---- files ----------------------------------------------------------------------------------

/// Reads a scan or model file in any supported format (by extension). STL gives its unique
/// vertices (bit-identical corners merged) as points, in order of first appearance.
Expected<Surface> read_surface(const std::string& path, const PointReadOptions& options = {});

/// read_surface without the triangles.
Expected<PointCloud> read_point_cloud(const std::string& path,
                                      const PointReadOptions& options = {});

/// Reads the triangles of an STL or PLY file (vertices = the file's unique points). A file
/// without triangles is an error.
Expected<TriangleMesh> read_mesh(const std::string& path);

/// Writes in the format of the extension, atomically (write_file_atomically). PLY writes every
/// attribute present (normals, colours, scalars, face ids, triangles); XYZ writes x y z, then
/// nx ny nz when present, then the scalar when present; STL needs triangles.
Expected<bool> write_surface(const std::string& path, const Surface& surface,
                             const PointWriteOptions& options = {});

/// write_surface without triangles.
Expected<bool> write_point_cloud(const std::string& path, const PointCloud& cloud,
                                 const PointWriteOptions& options = {});

/// Writes a mesh as binary STL or as PLY (vertices + faces), by extension.
Expected<bool> write_mesh(const std::string& path, const TriangleMesh& mesh,
                          const PointWriteOptions& options = {});

// ---- memory (tests, fuzzing, network payloads) ----------------------------------------------
// `name` only labels error messages (usually the file path).

Expected<Surface> parse_ply(std::string_view bytes, const std::string& name,
                            const PointReadOptions& options = {});
Expected<Surface> parse_xyz(std::string_view text, const std::string& name);
Expected<Surface> parse_stl(std::string_view bytes, const std::string& name);
Expected<Surface> parse_surface(std::string_view bytes, PointFormat format, const std::string& name,
                                const PointReadOptions& options = {});

/// The file contents write_surface would write; an error for inconsistent attributes, triangle
/// indices out of range, or STL without triangles.
Expected<std::string> format_ply(const Surface& surface, const PointWriteOptions& options = {});
Expected<std::string> format_xyz(const Surface& surface);
Expected<std::string> format_stl(const Surface& surface);
Expected<std::string> format_surface(const Surface& surface, PointFormat format,
                                     const PointWriteOptions& options = {});

}  // namespace springscan::analysis
