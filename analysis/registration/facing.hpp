#pragma once
// Solid sheets seen from one side. A CAD solid has two skins a sheet thickness apart, its
// samples' normals pointing out of the material; a scanner sees one skin, its points' normals
// pointing back at the scanner. The nearest model sample of a scan point may lie on either skin
// (the fit starts a few millimetres off, and 1-2 mm is all that separates them), and a fit that
// pairs with the far skin settles one thickness off or chooses the part turned over. The rule
// here: a scan point pairs only with model samples that face the same way as the point, once
// the point's normal is turned into the model frame (their normals agree in sign). Used by
// every pairing of the global fit: the PCA candidates, the orientation choice and the final ICP.

#include <cstddef>
#include <cstdint>
#include <optional>
#include <vector>

#include "analysis/core/kdtree.hpp"
#include "analysis/core/part_model.hpp"
#include "analysis/registration/icp.hpp"

namespace springscan::analysis {

/// A scan point whose kFacingRank nearest samples all face away lies off its skin (at an edge, or
/// with a poorly estimated normal): it gets no pair rather than one across the part.
inline constexpr std::size_t kFacingRank = 16;

/// The nearest of `tree`'s points within `max_distance` whose normal (`normals`, one per point)
/// has a positive dot product with `normal`, when it is among the query's kFacingRank nearest
/// (KdTree::nearest_along); the nearest point when `normal` is zero (a scan point whose normal
/// is undefined). Nothing otherwise.
/// With `min_dot` the dot product must exceed that instead (unit normals: the cosine of the
/// largest angle between them).
std::optional<Neighbor> nearest_facing(const KdTree& tree, const std::vector<Vec3>& normals,
                                       const Vec3& query, const Vec3& normal,
                                       double max_distance_mm, double min_dot = 0.0);

/// The squared distance from `query` to the nearest sample facing `normal` (as nearest_facing,
/// no limit); infinity when no sample faces that way.
double facing_squared_distance(const KdTree& tree, const std::vector<Vec3>& normals,
                               const Vec3& query, const Vec3& normal);

/// ICP pairs by nearest_facing: source point i with normal T.linear() * source_normals[i].
/// Holds references to all three vectors; `source_normals` must have one normal per point of
/// the source the search is called with, `normals` one per tree point.
IcpPairSearch nearest_facing_pairs(const KdTree& tree, const std::vector<Vec3>& normals,
                                   const std::vector<Vec3>& source_normals, double max_distance_mm,
                                   double min_dot = 0.0);

/// ICP pairs on the exact surface: the foot and normal of the closest point, within
/// `max_distance_mm` (0: no limit); with `source_normals` (a one-sided scan of a solid) only a
/// foot whose normal faces the point's way, as nearest_facing_pairs does on samples; empty: any
/// foot. Holds references to `exact` and `source_normals`.
IcpPairSearch exact_surface_pairs(const SurfaceDistance& exact,
                                  const std::vector<Vec3>& source_normals, double max_distance_mm);

/// An evenly strided sample of points with their normals picked alike (strided_sample picks by
/// position in the vector only); `normals` empty when the source has none (no facing rule).
struct FacingSample {
  std::vector<Vec3> points;
  std::vector<Vec3> normals;
};

inline FacingSample facing_sample(const std::vector<Vec3>& points, const std::vector<Vec3>& normals,
                                  std::size_t count) {
  FacingSample out{strided_sample(points, count), {}};
  if (!points.empty() && normals.size() == points.size())
    out.normals = strided_sample(normals, count);
  return out;
}

/// The estimated normals of a points-only scan of a solid with the sign of each that the scan
/// itself tells, and which signs it tells (`known`, one per point).
struct SkinNormals {
  std::vector<Vec3> normals;
  std::vector<std::uint8_t> known;
};

/// Signs estimated `normals` (of `points`, a one-sided scan of a solid) along each skin: a normal
/// facing `viewpoint` within 45 deg keeps its sign (no pass tilted less than 45 deg from the
/// viewpoint's direction sees a skin that faces away from it by 135 deg), those on a flat patch
/// first (every neighbour's normal within 30 deg: a plane estimated across a sheet seen on both
/// skins has a normal within the wall that may face the viewpoint), and the others get theirs
/// by growing each skin from those, over the k nearest points, the most parallel neighbour first
/// (Hoppe et al. 1992: the consistent orientation of a minimum spanning tree; Open3D's
/// orient_normals_consistent_tangent_plane). A standing wall's estimated normal is horizontal, and
/// the viewpoint, far above, decides its sign by a small vertical part: a guess. Grown along the
/// skin from the flange it bends from, its sign is the skin's. A step is taken only between points
/// within `max_off_skin_mm` of each other's tangent plane (the other skin lies a sheet thickness
/// away) whose normals are within 60 deg; a point no such step reaches keeps its normal, `known`
/// false.
SkinNormals orient_along_skins(const std::vector<Vec3>& points, const std::vector<Vec3>& normals,
                               const Vec3& viewpoint, double max_off_skin_mm);

/// The signs of a points-only scan's fit points' estimated `fit_normals` (the scan's voxel
/// centroids `fit_points`, voxels of `fit_voxel_mm`), grown along each skin (orient_along_skins)
/// on a finer sample of `scan_points` when the fit voxel is coarser than half the sheet
/// (`thickness_mm`): a fit voxel may then hold both skins of a wall, its centroid between them,
/// and a step between such centroids crossed the sheet (a points-only front panel, 2 mm thick,
/// fit voxels of 2.7 mm: 1,185 of 8,190 fit points signed against the scanner's normals, its
/// frame 0.27 mm off). The finer sample has one centroid per cube of half the sheet (none holds
/// both skins), its normals estimated anew toward `viewpoint` over its 10 nearest. A fit point
/// takes the sign its signed fine points within half a fit voxel agree on; where they disagree
/// (both skins in its voxel: its centroid lies off either) or none is signed, `known` is false.
/// `threads`: for the fine sample's neighbours and normals (0 = all cores).
SkinNormals orient_fit_points_along_skins(const std::vector<Vec3>& scan_points,
                                          const std::vector<Vec3>& fit_points,
                                          const std::vector<Vec3>& fit_normals, double fit_voxel_mm,
                                          const Vec3& viewpoint, double thickness_mm,
                                          int threads = 0);

/// True when every point of `points` has a normal and the rule can apply.
inline bool has_facing_normals(const std::vector<Vec3>& points, const std::vector<Vec3>& normals) {
  return !points.empty() && normals.size() == points.size();
}

}  // namespace springscan::analysis
