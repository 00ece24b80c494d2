#pragma once
// The ICP engine (paper §3 and §4), the one both fits use: the global fit
// (analysis/registration/global_fit.hpp) and the local best fits
// (analysis/springback/local_fit.hpp) are its two clients, each mapping its own settings onto
// IcpSettings. Alternately pair every source point with a target partner and solve for the rigid
// motion that minimises the error of the pairs:
//   * terms: point-to-point (Besl-McKay, closed form via SVD) or point-to-plane (Chen-Medioni,
//     linearised 6x6 solve in which directions the data do not constrain are held still);
//   * rejection: a maximum pair distance, trimming of the farthest pairs, a residual threshold
//     of a few robust sigmas; weighting by a Huber or Tukey kernel;
//   * one stop test: iterations, error, the ratio E(i)/E(i-1) (paper Figure 6b), a negligible
//     update.
// The pair search is the client's (nearest model point, or the exact CAD surface); everything
// after it is shared (analysis/registration/icp_terms.hpp holds the per-pair terms).

#include <cstddef>
#include <functional>
#include <numbers>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "analysis/core/expected.hpp"
#include "analysis/core/kdtree.hpp"
#include "analysis/core/point_cloud.hpp"

namespace springscan::analysis {

enum class IcpMethod { kPointToPoint, kPointToPlane };
enum class RobustKernel { kNone, kHuber, kTukey };

/// What ended an ICP run. kIncrement, kError and kRatio count as converged.
enum class IcpStop { kIncrement, kError, kRatio, kIterations, kTooFewPairs, kNumericalFailure };
std::string_view to_string(IcpStop stop);

/// The most of the pairs trimming may leave out: some pairs must remain to fit.
inline constexpr double kMaxTrimmedFraction = 0.99;

/// The engine's settings; each field's range is checked once, in validate() below.
struct IcpSettings {
  IcpMethod method = IcpMethod::kPointToPlane;  ///< point-to-plane needs target normals
  int max_iterations = 50;       ///< pair searches followed by an update, at most, [0, 10000]
  int max_inner_iterations = 1;  ///< updates on one set of pairs (Gauss-Newton steps), [1, 1000]
  double max_correspondence_distance_mm = 0.0;  ///< pairs farther apart are dropped; 0 = no limit
  double trimmed_fraction = 0.1;     ///< share of the farthest pairs left out each search, <= 0.99
  double inlier_sigma_factor = 0.0;  ///< residuals beyond this many robust sigmas (1.4826 x the
                                     ///< median |residual|) are left out at each update; 0 = off
  double min_inlier_threshold_mm = 0.0;        ///< that residual threshold never goes below this
  RobustKernel kernel = RobustKernel::kHuber;  ///< weight of a pair by its residual
  double kernel_scale_mm = 1.0;                ///< Huber corner / Tukey cut-off, mm
  double degenerate_eigenvalue_ratio = 1e-10;  ///< point-to-plane: directions whose eigenvalue
                                               ///< is below this x the largest are held still
                                               ///< (rotation scaled by the source's rms radius)
  int min_pairs = 0;          ///< fewer kept pairs stop the run; 0 = the metric's unknowns (6 or 3)
  double min_error_mm = 0.0;  ///< stop when the rms residual falls to this (converged); 0 = off
  double error_ratio_stop = 0.9999;  ///< stop when E(i)/E(i-1) > this, from i = 2 (converged);
                                     ///< 0 = off
  /// Converged when an update on fresh pairs turns less than this (default 1e-10 rad) ...
  double convergence_rotation_deg = 1e-10 * 180.0 / std::numbers::pi;
  double convergence_translation_mm = 1e-9;  ///< ... and moves less than this
  int threads = 0;                           ///< worker threads, 0 = all cores
};

struct IcpResult {
  Transform T_target_source = Transform::Identity();  ///< maps source into the target frame
  std::vector<double> error_history;    ///< E(i), mm^2: mean squared residual of the kept pairs
                                        ///< at the start of pair set i (E(0): the initial
                                        ///< transform); after a negligible update, E at the end
  int iterations = 0;                   ///< pair sets solved (= updates when one per set)
  int updates = 0;                      ///< updates applied
  std::size_t inliers = 0;              ///< pairs kept in the last evaluation
  bool converged = false;               ///< stopped by error, ratio or increment (not iterations)
  bool degenerate = false;              ///< point-to-plane: some motion was unconstrained (a plane)
  int determined_directions = 0;        ///< of 6, in the last update; a flat surface gives 3
  IcpStop stop = IcpStop::kIterations;  ///< what ended the run
  std::string stop_reason;  ///< "increment", "error", "ratio", "iterations", "too few pairs", ...
  double rms_mm() const;    ///< sqrt of the last E, or 0 without history
};

/// A source point's partner on the target.
struct IcpPair {
  Vec3 point = Vec3::Zero();          ///< the partner
  Vec3 normal = Vec3::Zero();         ///< the target's unit normal there (point-to-plane)
  double squared_distance_mm2 = 0.0;  ///< |T x - point|^2 at the search, for trimming
  bool valid = false;                 ///< false: no partner within the distance limit
};

/// Writes pairs[i], for every i in [begin, end), the partner of T * source[i]. Called from the
/// worker threads, one block of points at a time; must write nothing else.
using IcpPairSearch =
    std::function<void(const std::vector<Vec3>& source, const Transform& T, std::size_t begin,
                       std::size_t end, std::vector<IcpPair>& pairs)>;

/// The nearest point of `tree` within `max_distance_mm` (0 = no limit), with normals[index]
/// when `normals` has one per point. Holds references to both. A valid pairs[i] on entry must be
/// this search's pair from an earlier pose (as icp() keeps them): its distance bounds the search.
IcpPairSearch nearest_point_pairs(const KdTree& tree, const std::vector<Vec3>& normals,
                                  double max_distance_mm);

/// The engine: registers `source` (finite, not empty) to whatever `search` pairs it with,
/// starting from `initial`. Thread-safe for concurrent calls; the result does not depend on
/// `threads` (fixed blocks, partial sums combined in block order).
/// Errors: invalid settings only; running out of pairs is a result (IcpStop::kTooFewPairs).
Expected<IcpResult> icp(const std::vector<Vec3>& source, const IcpPairSearch& search,
                        const Transform& initial, const IcpSettings& settings);

/// Registers `source` to the points of `target` (its nearest point) starting from `initial`.
/// `target_normals` (unit, one per target point) are needed for point-to-plane, ignored
/// otherwise. Errors: empty input, non-finite coordinates, missing normals, invalid settings.
Expected<IcpResult> icp(const std::vector<Vec3>& source, const KdTree& target,
                        const std::vector<Vec3>& target_normals,
                        const Transform& initial = Transform::Identity(),
                        const IcpSettings& settings = {});

/// The settings' first out-of-range field as "<context><field> = value: allowed range", or
/// nothing. Each field has one range, checked here only (the proto loader calls this too).
std::optional<Error> validate(const IcpSettings& settings, std::string_view context = "icp: ");

}  // namespace springscan::analysis
