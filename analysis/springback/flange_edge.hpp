#pragma once
// The free edge of an end flange against the CAD edge (docs/springback.md "Flange end
// position"): where the sheet ends, along the sheet (in-plane: overhang > 0, draw-in < 0) and
// across it (height along the flange's CAD normal), in strips along the edge.
//
// CAD edge: the exact closest point of the model surface (PartModel::distance) to a point a
// little beyond the strip's outermost sample, in the flange's plane, at each strip's centre:
// the foot lies on the edge. Only a straight CAD edge is measured (the feet on one line within
// max_edge_bend_mm). Scan edge: a straight line along the edge (a straight CAD edge stays
// straight under the motions of a flange), the lowest line above all the flange's points within
// `band_mm` inside the CAD edge (their upper convex hull), moved out by band_mm / n for the n
// points; evaluated at each strip's centre; its height is the flange's fitted surface there
// (FlangeShape), so noise along the normal does not enter.
//
// Thread safety: pure function (SurfaceDistance::closest is thread-safe).

#include <cstdint>
#include <span>
#include <vector>

#include "analysis/core/part_model.hpp"
#include "analysis/springback/flange_shape.hpp"

namespace springscan::analysis {

struct FlangeEdgeSettings {
  double strip_length_mm = 20.0;  ///< one strip along the edge per this length
  int min_strips = 3;             ///< and at least this many
  double band_mm = 5.0;           ///< the scan points this far inside the CAD edge estimate it
  int min_points_per_strip = 20;  ///< a strip with fewer: the edge is not measured
  /// A CAD edge whose strips' edge points leave a straight line by more than this is not
  /// measured (tabs, notches, curved outlines).
  double max_edge_bend_mm = 0.05;
};

/// Deviation of the free edge from the CAD edge, over the strips along it (mm).
struct EdgeDeviation {
  bool measured = false;  ///< false: not an end flange, no exact CAD surface, a CAD edge that
                          ///< is not straight, or a strip with too few points near the edge
  int strips = 0;
  double in_plane_mean_mm = 0.0, in_plane_min_mm = 0.0, in_plane_max_mm = 0.0;
  double across_mean_mm = 0.0, across_min_mm = 0.0, across_max_mm = 0.0;
  /// At each strip's centre, in the frame of the scan points given (the result frame): where
  /// the CAD edge is and where the scan's edge is. The report draws them on the deviation map.
  std::vector<Vec3> cad_edge, scan_edge;
};

/// The free edge of `flange` (the side away from `bend_axis_point`, its only bend's axis), from
/// its fitted `shape` and the scan `points` in use: those within band_mm of the CAD edge (inside
/// or beyond it), within the flange's extent along it and on its fitted surface (within its
/// inlier threshold). Not the flange's assigned points: the assignment leaves out those next to
/// its outline (the bend margin around a solid's end face, and points nearer an end-face sample
/// than a flange sample), and a solid's edge then read 0.05-1.5 mm short. Unmeasured when the
/// model has no exact distance or the shape was not measured.
EdgeDeviation measure_free_edge(const PartModel& model, const Flange& flange,
                                const FlangeShape& shape, const Vec3& bend_axis_point,
                                const PointCloud& scan, std::span<const std::uint32_t> points,
                                const FlangeEdgeSettings& settings = {});

}  // namespace springscan::analysis
