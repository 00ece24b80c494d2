#pragma once
// Deviation (DESIGN.md stage 5): the signed distance of every scan point (already in the CAD
// frame) to the model surface, positive on the side the surface normal points to, and its
// statistics. Exact CAD distance through PartModel::distance when the model has it; otherwise
// the distance to the tangent plane of the nearest model sample (sign by the sample normal).
// The stage measures and does not judge: the surface tolerance, and with it the share of points
// out of tolerance, belong to the verdict (analysis/inspection/verdict.hpp).

#include <cstddef>
#include <vector>

#include "analysis/core/expected.hpp"
#include "analysis/core/kdtree.hpp"
#include "analysis/core/part_model.hpp"
#include "analysis/core/point_cloud.hpp"

namespace springscan::analysis {

struct DeviationSettings {
  double color_scale_mm = 0.0;  ///< |d| shown as full blue/red; 0 = the verdict's surface
                                ///< tolerance_mm (the pipeline fills it in)
  double cell_size_mm = 0.0;    ///< grid of the batched nearest search; 0 = 3 x the median
                                ///< model sample spacing (speed only: the result is exact)
  int threads = 0;              ///< worker threads, 0 = all cores; no effect on the result
};

struct DeviationStatistics {
  double min_mm = 0.0;
  double max_mm = 0.0;
  double mean_mm = 0.0;
  double rms_mm = 0.0;
  double p95_mm = 0.0;     ///< 95th percentile of |d| (nearest rank)
  std::size_t points = 0;  ///< distances the statistics are taken over (0: none computed)
  /// Expanded uncertainties (k = 2; docs/uncertainty.md) of p95_mm and of the largest |d|,
  /// filled by the uncertainty stage.
  double p95_uncertainty_mm = 0.0;
  double max_uncertainty_mm = 0.0;
};

struct DeviationResult {
  std::vector<double> signed_distance_mm;  ///< one per scan point, in input order
  DeviationStatistics statistics;
  bool exact = false;  ///< true: CAD surface distance; false: model sample tangent planes
};

/// Signed deviation of `scan_in_cad` from `model`. `model_tree` must index model.samples.points
/// (it is only used without model.distance). Thread-safe; O(n log m) with samples.
/// Errors: non-finite points, samples without normals, a tree that does not match the samples.
Expected<DeviationResult> signed_deviation(const std::vector<Vec3>& scan_in_cad,
                                           const PartModel& model, const KdTree& model_tree,
                                           const DeviationSettings& settings = {});

/// The nearest model sample (index into model_tree) of every point, exactly (ties: the lowest
/// index). Points are grouped in grid cells; one radius query per cell bounds every cell
/// point's candidates, so most points need only a short brute force. Parallel, deterministic.
std::vector<std::uint32_t> nearest_samples(const std::vector<Vec3>& points,
                                           const KdTree& model_tree,
                                           const DeviationSettings& settings = {});

/// Statistics of signed distances (deterministic, exact percentile).
DeviationStatistics deviation_statistics(const std::vector<double>& signed_distance_mm);

/// Root mean square of `values` over the smallest (1 - trimmed_fraction) of their magnitudes
/// (outliers left out), mm; 0 for none. trimmed_fraction is clamped to [0, 0.99].
/// Deterministic: the kept values are summed in a fixed order.
double trimmed_rms(std::vector<double> values, double trimmed_fraction);

/// The deviation.ply colour map: blue (-scale) .. green (0) .. red (+scale), linear, saturated.
Rgb deviation_color(double signed_distance_mm, double scale_mm);

}  // namespace springscan::analysis
