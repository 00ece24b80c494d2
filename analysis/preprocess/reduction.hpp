#pragma once
// The pipeline's reduce stage (DESIGN.md stage 3): a voxel reduction of the scan for the
// global fit, and the paper's k-center reduction of model and scan (paper §2, for the
// deformation field). The deviation later uses every scan point, not these reductions.

#include <cstddef>

#include "analysis/core/expected.hpp"
#include "analysis/core/point_cloud.hpp"
#include "analysis/preprocess/curvature.hpp"
#include "analysis/preprocess/decimation.hpp"
#include "analysis/preprocess/kcenter.hpp"
#include "analysis/preprocess/voxel.hpp"

namespace springscan::analysis {

struct ReductionSettings {
  double voxel_size_mm = 0.0;  ///< scan voxel for the fit; 0 = auto: the scan's box diagonal
                               ///< divided by `auto_voxel_divisions`
  double auto_voxel_divisions = 150.0;  ///< see voxel_size_mm (a few thousand fit points)
  double min_voxel_fill = 0.1;          ///< voxels with fewer points than this share of the median
                                ///< voxel's count are left out of the fit: isolated outliers
                                ///< would otherwise weigh as much as a full voxel of surface
  KCenterSettings kcenter;             ///< w = 10 mm by default (paper Figure 3)
  CurvatureSettings curvature;         ///< minC; a library stage, not run by the pipeline
  DecimationSettings mesh_decimation;  ///< a scan given as a mesh, before everything else
};

struct ReductionOutcome {
  PointCloud scan_for_fit;                ///< voxel centroids of the scan
  double voxel_size_mm = 0.0;             ///< the voxel edge used
  std::size_t sparse_voxels_dropped = 0;  ///< voxels left out by min_voxel_fill
  std::vector<Vec3> model_centers;        ///< k-center reduction of the model samples
  std::vector<Vec3> scan_centers;         ///< k-center reduction of the voxel-reduced scan
  double model_covering_radius_mm = 0.0;
  double scan_covering_radius_mm = 0.0;
};

/// Reduces scan and model. Errors: empty or non-finite clouds, settings out of range.
Expected<ReductionOutcome> reduce(const PointCloud& scan, const PointCloud& model_samples,
                                  const ReductionSettings& settings = {});

/// Smallest box corner, largest box corner; both zero for an empty set.
std::pair<Vec3, Vec3> bounding_box(const std::vector<Vec3>& points);

}  // namespace springscan::analysis
