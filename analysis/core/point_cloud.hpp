#pragma once
// The one point-cloud type of springscan (STYLE.md §2): parallel vectors of Eigen fixed-size
// vectors. `points` is always filled; every other vector is either empty or has one entry per
// point. Coordinates are millimetres.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace springscan::analysis {

using Vec3 = Eigen::Vector3d;
using Mat3 = Eigen::Matrix3d;
/// A rigid transform. Named `T_<to>_<from>` in code: `T_cad_scan` maps scan into the CAD frame.
using Transform = Eigen::Isometry3d;
using Rgb = std::array<std::uint8_t, 3>;

struct PointCloud {
  std::vector<Vec3> points;            ///< positions, mm
  std::vector<Vec3> normals;           ///< unit normals, or empty
  std::vector<double> scalars;         ///< one value per point (e.g. signed deviation), or empty
  std::vector<Rgb> colors;             ///< per-point colour, or empty
  std::vector<std::int32_t> face_ids;  ///< CAD face id per point (model samples), or empty

  std::size_t size() const { return points.size(); }
  bool empty() const { return points.empty(); }
  bool has_normals() const { return !normals.empty(); }
  bool has_scalars() const { return !scalars.empty(); }
  bool has_colors() const { return !colors.empty(); }
  bool has_face_ids() const { return !face_ids.empty(); }

  /// True when every optional attribute is empty or has exactly one entry per point.
  bool attributes_consistent() const {
    const auto fits = [n = size()](std::size_t m) { return m == 0 || m == n; };
    return fits(normals.size()) && fits(scalars.size()) && fits(colors.size()) &&
           fits(face_ids.size());
  }
};

/// A triangle mesh (STL or PLY faces). Indices refer to `vertices`.
struct TriangleMesh {
  std::vector<Vec3> vertices;
  std::vector<std::array<std::uint32_t, 3>> triangles;
};

/// Returns the cloud with every point (and normal) mapped by T.
PointCloud transformed(const PointCloud& cloud, const Transform& T);

/// Keeps the points at `indices`, with their attributes, in that order.
PointCloud select(const PointCloud& cloud, const std::vector<std::uint32_t>& indices);

/// One point of every run of `stride` consecutive points, the stride chosen so that at most
/// `count` remain (all points when there are no more than `count`, or count is 0). The offset
/// within each run is a fixed hash of the run's number: deterministic, yet a cloud in scan-line
/// order, or with every 50th point an outlier, does not alias into a sample of one column or of
/// outliers only (a plain stride did, and the global fit then scored every pose on outliers).
std::vector<Vec3> strided_sample(const std::vector<Vec3>& points, std::size_t count);

}  // namespace springscan::analysis
