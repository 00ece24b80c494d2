// PLY reader: header (ply_format.cpp), then each element's body in declaration order. The vertex
// element fills the cloud, the face element the triangles; every other element is walked over.
#include <cstring>

#include "analysis/io/io_text.hpp"
#include "analysis/io/ply_body.hpp"
#include "analysis/io/ply_format.hpp"
#include "analysis/io/point_io.hpp"

namespace springscan::analysis {
namespace {

using io_detail::PlyBodyFormat;
using io_detail::PlyElement;
using io_detail::PlyHeader;
using io_detail::Target;
using io_detail::VertexLayout;

// Names tried, in order, for PointCloud::scalars when the caller names none.
bool is_default_scalar_name(const std::string& name) {
  return name == "scalar" || name.rfind("scalar_", 0) == 0 || name == "signed_deviation_mm" ||
         name == "deviation" || name == "quality" || name == "intensity";
}

Target target_for(const std::string& name) {
  static const std::pair<const char*, Target> kNames[] = {
      {"x", Target::kX},
      {"y", Target::kY},
      {"z", Target::kZ},
      {"nx", Target::kNx},
      {"ny", Target::kNy},
      {"nz", Target::kNz},
      {"normal_x", Target::kNx},
      {"normal_y", Target::kNy},
      {"normal_z", Target::kNz},
      {"red", Target::kRed},
      {"green", Target::kGreen},
      {"blue", Target::kBlue},
      {"diffuse_red", Target::kRed},
      {"diffuse_green", Target::kGreen},
      {"diffuse_blue", Target::kBlue},
      {"face_id", Target::kFaceId},
  };
  for (const auto& [n, t] : kNames) {
    if (name == n) return t;
  }
  return Target::kSkip;
}

// Which cloud attribute each vertex property feeds; attributes given only in part (nx without
// nz, red without blue) are skipped rather than half filled.
Expected<VertexLayout> vertex_layout(const PlyElement& vertex, const PointReadOptions& options,
                                     const std::string& name) {
  VertexLayout layout;
  int seen[static_cast<int>(Target::kCount)] = {};
  for (const auto& property : vertex.properties) {
    Target t = property.is_list ? Target::kSkip : target_for(property.name);
    if (t == Target::kSkip && !property.is_list && !seen[static_cast<int>(Target::kScalar)]) {
      const bool wanted = options.scalar_property.empty()
                              ? is_default_scalar_name(property.name)
                              : property.name == options.scalar_property;
      if (wanted) t = Target::kScalar;
    }
    if (t != Target::kSkip && seen[static_cast<int>(t)]++) t = Target::kSkip;  // duplicate name
    layout.targets.push_back(t);
    layout.types.push_back(property.type);
  }
  const auto all = [&](Target a, Target b, Target c) {
    return seen[static_cast<int>(a)] && seen[static_cast<int>(b)] && seen[static_cast<int>(c)];
  };
  if (!all(Target::kX, Target::kY, Target::kZ)) {
    return fail(ErrorCode::kCorruption, name + ": PLY element 'vertex' (header line " +
                                            std::to_string(vertex.header_line) +
                                            ") lacks property x, y or z");
  }
  if (!options.scalar_property.empty() && !seen[static_cast<int>(Target::kScalar)]) {
    return fail(ErrorCode::kCorruption,
                name + ": PLY element 'vertex' has no property '" + options.scalar_property + "'");
  }
  layout.normals = all(Target::kNx, Target::kNy, Target::kNz);
  layout.colors = all(Target::kRed, Target::kGreen, Target::kBlue);
  layout.scalars = seen[static_cast<int>(Target::kScalar)] != 0;
  layout.face_ids = seen[static_cast<int>(Target::kFaceId)] != 0;
  for (auto& t : layout.targets) {
    const bool drop =
        (!layout.normals && (t == Target::kNx || t == Target::kNy || t == Target::kNz)) ||
        (!layout.colors && (t == Target::kRed || t == Target::kGreen || t == Target::kBlue));
    if (drop) t = Target::kSkip;
  }
  return layout;
}

// Allocates the attributes the layout fills; `count` has been checked against the file size.
void allocate(PointCloud& cloud, const VertexLayout& layout, std::size_t count) {
  cloud.points.assign(count, Vec3::Zero());
  if (layout.normals) cloud.normals.assign(count, Vec3::Zero());
  if (layout.colors) cloud.colors.assign(count, Rgb{0, 0, 0});
  if (layout.scalars) cloud.scalars.assign(count, 0.0);
  if (layout.face_ids) cloud.face_ids.assign(count, 0);
}

// The first non-finite coordinate, normal or scalar, named with its vertex index.
std::optional<Error> check_finite(const PointCloud& cloud, const std::string& name) {
  for (std::size_t i = 0; i < cloud.points.size(); ++i) {
    if (!cloud.points[i].allFinite()) {
      return fail(ErrorCode::kCorruption, name + ": vertex " + std::to_string(i) +
                                              " has a non-finite coordinate (NaN or Inf)");
    }
  }
  for (std::size_t i = 0; i < cloud.normals.size(); ++i) {
    if (!cloud.normals[i].allFinite()) {
      return fail(ErrorCode::kCorruption,
                  name + ": vertex " + std::to_string(i) + " has a non-finite normal (NaN or Inf)");
    }
  }
  for (std::size_t i = 0; i < cloud.scalars.size(); ++i) {
    if (!std::isfinite(cloud.scalars[i])) {
      return fail(ErrorCode::kCorruption,
                  name + ": vertex " + std::to_string(i) + " has a non-finite scalar (NaN or Inf)");
    }
  }
  return std::nullopt;
}

std::optional<Error> check_indices(const Surface& surface, const std::string& name) {
  const std::size_t n = surface.cloud.points.size();
  for (std::size_t f = 0; f < surface.triangles.size(); ++f) {
    for (auto index : surface.triangles[f]) {
      if (index >= n) {
        return fail(ErrorCode::kCorruption, name + ": triangle " + std::to_string(f) +
                                                " refers to vertex " + std::to_string(index) +
                                                " but there are " + std::to_string(n) +
                                                " vertices");
      }
    }
  }
  return std::nullopt;
}

// The index of the face element's vertex list property, if it has one.
std::optional<std::size_t> face_list_property(const PlyElement& face) {
  for (std::size_t i = 0; i < face.properties.size(); ++i) {
    const auto& p = face.properties[i];
    if (p.is_list && (p.name == "vertex_indices" || p.name == "vertex_index")) return i;
  }
  return std::nullopt;
}

}  // namespace

Expected<Surface> parse_ply(std::string_view bytes, const std::string& name,
                            const PointReadOptions& options) {
  auto header = io_detail::parse_ply_header(bytes, name);
  if (!header) return header.error();
  const PlyElement* vertex = nullptr;
  for (const auto& element : header->elements) {
    if (element.name == "vertex") vertex = &element;
  }
  if (vertex == nullptr)
    return fail(ErrorCode::kCorruption, name + ": PLY file has no 'vertex' element");
  auto layout = vertex_layout(*vertex, options, name);
  if (!layout) return layout.error();

  io_detail::PlyBody body(bytes, *header, name);
  Surface surface;
  bool vertices_read = false;
  for (const auto& element : header->elements) {
    if (auto error = body.check_fits(element)) return *error;
    std::optional<Error> error;
    if (&element == vertex && !vertices_read) {
      allocate(surface.cloud, *layout, static_cast<std::size_t>(element.count));
      error = body.read_vertices(element, *layout, surface.cloud);
      vertices_read = true;
    } else if (element.name == "face" && options.read_faces && face_list_property(element)) {
      error = body.read_faces(element, *face_list_property(element), surface.triangles);
    } else {
      error = body.skip(element);
    }
    if (error) return *error;
  }
  if (auto error = check_finite(surface.cloud, name)) return *error;
  if (auto error = check_indices(surface, name)) return *error;
  return surface;
}

}  // namespace springscan::analysis
