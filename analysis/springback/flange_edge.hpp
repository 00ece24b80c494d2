#pragma once
// A flange's trim edges against the CAD edges (docs/springback.md "Flange end position"): where
// the sheet ends, along the sheet (in-plane: overhang > 0, draw-in < 0) and across it (height
// along the flange's CAD normal), in strips along each edge. The free edge of an end flange
// (opposite its only bend) is one of them; the side edges of a profile, the free edges of a
// flange with two bends and every other straight piece of a flange's outline are the others.
//
// Candidate edges: the convex hull of the flange's model samples (the scanned skin) in its
// plane, cut into straight runs where it turns by more than corner_angle_deg. A run is a trim
// edge where the CAD surface ends there: the exact closest point of the model surface
// (PartModel::distance) to a point a little beyond the strip's outermost sample, in the
// flange's plane, at each strip's centre, lies on the edge, and not on a bend's face (the side
// of a flange a bend continues). Only a straight CAD edge is measured (the feet on one line
// within max_edge_bend_mm): an outline the hull bridges (a notch, a tab) is left out.
//
// Scan edge: a straight line along the edge (a straight CAD edge stays straight under the
// motions of a flange), the lowest line above all the flange's points within `band_mm` inside
// the CAD edge (their upper convex hull), moved out by band_mm / n for the n points; evaluated
// at each strip's centre; its height is the flange's fitted surface there (FlangeShape), so
// noise along the normal does not enter.
//
// Thread safety: pure function (SurfaceDistance::closest is thread-safe).

#include <cstdint>
#include <span>
#include <string_view>
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
  double min_edge_length_mm = 15.0;  ///< shorter straight pieces of the outline are left out
  double corner_angle_deg = 20.0;    ///< the outline turns by more: a new edge begins
};

/// Which trim edge: an end flange's free edge (opposite its only bend, parallel to it), or any
/// other straight piece of a flange's outline.
enum class EdgeKind { kFree, kSide };

/// "free" or "side": the report's `kind`.
std::string_view edge_kind_name(EdgeKind kind);

/// Deviation of a trim edge from the CAD edge, over the strips along it (mm).
struct EdgeDeviation {
  bool measured = false;
  EdgeKind kind = EdgeKind::kSide;
  Vec3 direction = Vec3::Zero();  ///< along the CAD edge, unit (frame of the points given)
  Vec3 outward = Vec3::Zero();    ///< in the flange's plane, out of the material, unit
  double length_mm = 0.0;         ///< the length of outline the strips cover
  int strips = 0;
  double in_plane_mean_mm = 0.0, in_plane_min_mm = 0.0, in_plane_max_mm = 0.0;
  double across_mean_mm = 0.0, across_min_mm = 0.0, across_max_mm = 0.0;
  /// At each strip's centre, in the frame of the scan points given (the result frame): where
  /// the CAD edge is and where the scan's edge is. The report draws them on the deviation map.
  std::vector<Vec3> cad_edge, scan_edge;
  /// Expanded (k = 2) of its in-plane and across moves, each with the result frame's move at
  /// the edge along that direction (docs/uncertainty.md); uncertainty_mm the larger of the two.
  double in_plane_uncertainty_mm = 0.0, across_uncertainty_mm = 0.0;
  double uncertainty_mm = 0.0;
};

/// The measured trim edges of `flange` (outline order), from its fitted `shape` and the scan
/// `points` in use: those within band_mm of a CAD edge (inside or beyond it), within the edge's
/// extent along it and on the flange's fitted surface (within its inlier threshold). Not the
/// flange's assigned points: the assignment leaves out those next to its outline (the bend
/// margin around a solid's end face, and points nearer an end-face sample than a flange
/// sample), and a solid's edge then read 0.05-1.5 mm short. `end_bend`: the flange's only bend
/// when it is an end flange (its free edge is the edge parallel to it on the far side), else
/// null. An edge with a strip the scan does not reach is left out. None when the model has no
/// exact distance or the shape was not measured.
std::vector<EdgeDeviation> measure_trim_edges(const PartModel& model, const Flange& flange,
                                              const FlangeShape& shape, const Bend* end_bend,
                                              const PointCloud& scan,
                                              std::span<const std::uint32_t> points,
                                              const FlangeEdgeSettings& settings = {});

}  // namespace springscan::analysis
