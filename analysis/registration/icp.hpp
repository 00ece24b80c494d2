#pragma once
// ICP (paper §3): alternately pair every source point with its nearest target point and solve
// for the rigid motion that minimises the error of the pairs. Point-to-point (Besl-McKay,
// closed form via SVD) or point-to-plane (Chen-Medioni, linearised 6x6 solve). Robustness:
// a maximum pair distance, trimming of the worst pairs and a Huber or Tukey kernel.
// Stops on iterations, on error, on the ratio E(i)/E(i-1) (paper Figure 6b), or when the
// update becomes negligible.

#include <cstddef>
#include <string>
#include <vector>

#include "analysis/core/expected.hpp"
#include "analysis/core/kdtree.hpp"
#include "analysis/core/point_cloud.hpp"

namespace springscan::analysis {

enum class IcpMethod { kPointToPoint, kPointToPlane };
enum class RobustKernel { kNone, kHuber, kTukey };

struct IcpSettings {
  IcpMethod method = IcpMethod::kPointToPlane;  ///< point-to-plane needs target normals
  int max_iterations = 50;                      ///< ICP updates at most
  double max_correspondence_distance_mm = 0.0;  ///< pairs farther apart are dropped; 0 = no limit
  double trimmed_fraction = 0.1;  ///< share of the farthest pairs left out each iteration, [0, 1)
  RobustKernel kernel = RobustKernel::kHuber;  ///< weight of a pair by its residual
  double kernel_scale_mm = 1.0;                ///< Huber corner / Tukey cut-off, mm
  double min_error_mm = 0.0;               ///< stop when the rms residual falls to this (converged)
  double error_ratio_stop = 0.9999;        ///< stop when E(i)/E(i-1) > this, from i = 2 (converged)
  double rotation_tolerance_rad = 1e-10;   ///< stop when an update rotates less than this ...
  double translation_tolerance_mm = 1e-9;  ///< ... and translates less than this (converged)
  int threads = 0;                         ///< worker threads, 0 = all cores
};

struct IcpResult {
  Transform T_target_source = Transform::Identity();  ///< maps source into the target frame
  std::vector<double> error_history;  ///< E(i), mm^2: mean squared residual of the kept pairs
                                      ///< at the i-th transform (E(0): the initial one)
  int iterations = 0;                 ///< updates applied
  std::size_t inliers = 0;            ///< pairs kept in the last evaluation
  bool converged = false;             ///< stopped by error, ratio or increment (not iterations)
  bool degenerate = false;  ///< point-to-plane: some motion was unconstrained (e.g. a plane)
  std::string stop_reason;  ///< "increment", "error", "ratio", "iterations", "too few pairs", ...
  double rms_mm() const;    ///< sqrt of the last E, or 0 without history
};

/// Registers `source` to the points of `target` starting from `initial`. `target_normals`
/// (unit, one per target point) are needed for point-to-plane, ignored otherwise. Thread-safe
/// for concurrent calls; the result does not depend on `threads`.
/// Errors: empty input, non-finite coordinates, missing normals, settings out of range.
Expected<IcpResult> icp(const std::vector<Vec3>& source, const KdTree& target,
                        const std::vector<Vec3>& target_normals,
                        const Transform& initial = Transform::Identity(),
                        const IcpSettings& settings = {});

/// The settings' first out-of-range field as "field = value: reason", or nothing.
std::optional<Error> validate(const IcpSettings& settings);

}  // namespace springscan::analysis
