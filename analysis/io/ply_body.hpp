#pragma once
// Internal to ply_read.cpp: reading the element records of a PLY body, ascii or binary, with
// every count and offset checked against the bytes that remain.

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "analysis/core/expected.hpp"
#include "analysis/core/point_cloud.hpp"
#include "analysis/io/io_text.hpp"
#include "analysis/io/ply_format.hpp"

namespace springscan::analysis::io_detail {

/// Where one vertex property goes in the cloud.
enum class Target : std::uint8_t {
  kSkip,
  kX,
  kY,
  kZ,
  kNx,
  kNy,
  kNz,
  kRed,
  kGreen,
  kBlue,
  kScalar,
  kFaceId,
  kCount
};

/// The per-property targets of the vertex element and the attributes they fill.
struct VertexLayout {
  std::vector<Target> targets;  ///< one per vertex property
  std::vector<PlyType> types;   ///< one per vertex property (item type for lists)
  bool normals = false;
  bool colors = false;
  bool scalars = false;
  bool face_ids = false;
};

/// Reads the body that follows a parsed header, element by element, in order.
/// Holds views of `bytes` and `name`: both must outlive it.
class PlyBody {
 public:
  PlyBody(std::string_view bytes, const PlyHeader& header, const std::string& name);

  /// An error when the element cannot fit in the bytes that remain (checked before anything is
  /// allocated for it), or when it declares records but no properties.
  std::optional<Error> check_fits(const PlyElement& element) const;
  /// Fills the allocated attributes of `cloud` (one entry per record).
  std::optional<Error> read_vertices(const PlyElement& element, const VertexLayout& layout,
                                     PointCloud& cloud);
  /// Appends the triangles of each polygon (fan triangulation) of list property `list`.
  std::optional<Error> read_faces(const PlyElement& element, std::size_t list,
                                  std::vector<std::array<std::uint32_t, 3>>& triangles);
  /// Walks over the element.
  std::optional<Error> skip(const PlyElement& element);

 private:
  // Calls on_value(property, value) for each scalar property and on_list(property, count) then
  // on_item(property, item) for each list; stops at the first error.
  template <typename OnValue, typename OnItem>
  std::optional<Error> walk_record(const PlyElement& element, std::uint64_t record,
                                   OnValue&& on_value, OnItem&& on_item);
  std::optional<Error> binary_value(PlyType type, const PlyElement& element, std::uint64_t record,
                                    double& value);
  std::optional<Error> ascii_value(const PlyElement& element, std::uint64_t record, double& value);
  std::optional<Error> read_vertices_fixed(const PlyElement& element, const VertexLayout& layout,
                                           PointCloud& cloud);
  Error error_at(const PlyElement& element, std::uint64_t record, const std::string& what) const;

  std::string_view bytes_;
  const std::string& name_;
  PlyBodyFormat format_;
  bool swap_;           // binary body in the other byte order than this machine
  std::size_t offset_;  // binary: the next byte to read
  TextCursor cursor_;   // ascii: the next token
};

}  // namespace springscan::analysis::io_detail
