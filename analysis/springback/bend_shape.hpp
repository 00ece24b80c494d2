#pragma once
// Beyond rigid flanges (docs/springback.md): the steps measure_springback runs after the local
// fits. Internal to analysis/springback: the model labels it shares with springback.cpp.

#include <cstdint>
#include <vector>

#include "analysis/springback/springback.hpp"

namespace springscan::analysis {

/// The bend-face samples of the model, one zone per (bend, face): a bend's faces may be both
/// sides of a solid sheet, and a cylinder is fitted to one side.
struct BendZones {
  struct Zone {
    std::size_t bend = 0;  ///< index into segmentation.bends
    int face = -1;
    double nominal_radius_mm = 0.0;  ///< mean distance of the face's samples from the axis
  };
  std::vector<Zone> zones;  ///< sample label flanges.size() + z
  /// Per bend: its samples' extent along its (segmentation) axis from its axis point.
  std::vector<double> t_min, t_max;
};

/// Labels every sample of a bend face (unlabelled until now) with its zone.
BendZones label_bend_zones(const PartModel& model, std::vector<std::int32_t>& labels);

/// Flange shapes, bend zone cylinders, the angle along each bend and, next to a curled
/// flange, the bend angle from the end tangent planes; into `result` (flanges and bends filled
/// by the local fits). `points`: the scan points in use (thinned; a free edge looks for
/// its points among all of them, the assignment leaves out those next to a flange's outline);
/// `zone_points[z]`: those assigned to zone z. Flanges, then
/// bends, run as parallel tasks on up to `threads` (0: all cores); the result does not depend
/// on it.
void measure_shapes(const PartModel& model, const PointCloud& scan,
                    const std::vector<std::uint32_t>& points, const BendZones& zones,
                    const std::vector<std::vector<std::uint32_t>>& zone_points,
                    const BendShapeSettings& settings, int threads, SpringbackResult& result);

}  // namespace springscan::analysis
