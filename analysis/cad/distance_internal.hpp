#pragma once
// PRIVATE to analysis/cad_distance*.cpp: per-face data of the exact distance (includes
// OpenCASCADE through cad_internal.hpp).

#include <array>
#include <vector>

#include "analysis/cad/internal.hpp"
#include "analysis/core/triangle_bvh.hpp"

namespace springscan::analysis {

/// Point location in a face's UV triangulation: a uniform grid of triangle lists.
class UvGrid {
 public:
  /// `ids`: the mesh triangle index of each UV triangle.
  void build(std::vector<std::array<Eigen::Vector2d, 3>> triangles, std::vector<std::uint32_t> ids);
  /// The mesh triangle containing uv (barycentric tolerance 1e-9 of its area), or -1.
  int locate(const Eigen::Vector2d& uv) const;
  /// True when uv lies in the grid's box grown by `margin`.
  bool in_box(const Eigen::Vector2d& uv, double margin) const;
  double u_min() const { return lo_.x(); }

 private:
  std::vector<std::array<Eigen::Vector2d, 3>> triangles_;
  std::vector<std::uint32_t> ids_;
  Eigen::Vector2d lo_ = Eigen::Vector2d::Zero(), hi_ = Eigen::Vector2d::Zero();
  Eigen::Vector2d cell_ = Eigen::Vector2d::Ones();
  int nu_ = 0, nv_ = 0;
  std::vector<std::uint32_t> start_;  // CSR: cell c holds items_[start_[c] .. start_[c + 1])
  std::vector<std::uint32_t> items_;
};

/// A boundary edge: segments and circular arcs in closed form, else projected by Extrema.
struct EdgeData {
  enum class Kind { kLine, kCircle, kOther };
  int edge_index = 0;  ///< 1-based index in the distance's edge map
  Kind kind = Kind::kOther;
  Vec3 a = Vec3::Zero(), b = Vec3::Zero();  ///< the edge's end points
  // Circles: P(t) = center + radius (cos t x + sin t y), t in [t0, t1].
  Vec3 center = Vec3::Zero(), x = Vec3::UnitX(), y = Vec3::UnitY();
  double radius = 0.0, t0 = 0.0, t1 = 0.0;
};

struct FaceData {
  AnalyticSurface surface;
  UvGrid grid;
  double slack_mm = 0.0;   ///< |true distance - mesh distance| bound: 2 deflection + margin
  std::vector<int> edges;  ///< indices into the edge table
};

/// The closest point of one face to q, with the outward normal there.
struct FaceFoot {
  bool valid = false;
  Vec3 point = Vec3::Zero();
  Vec3 normal = Vec3::UnitZ();
  double distance = 0.0;
};

/// Everything the queries read; immutable once built.
struct DistanceTables {
  std::vector<FaceData> faces;
  std::vector<EdgeData> edges;
  TopTools_IndexedMapOfShape edge_map;
};

DistanceTables build_distance_tables(const CadShape::Impl& shape, double margin_mm);

/// Closest point of face `face_id` to q. `seed`: the face's nearest triangle (UV seed for
/// non-analytic surfaces). Thread-safe: OpenCASCADE adaptors are local to the call.
FaceFoot foot_on_face(const CadShape::Impl& shape, const DistanceTables& tables, int face_id,
                      const Vec3& q, const TriangleFoot& seed);

}  // namespace springscan::analysis
