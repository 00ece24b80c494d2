#pragma once
// Local best fit (paper section 4): a subset of the scan, already in the CAD frame after the
// global fit, fitted on its own to the whole model by point-to-plane ICP (Chen-Medioni). A
// client of the one ICP engine (analysis/registration/icp.hpp): this file supplies the pair
// search (nearest model sample, or the exact CAD surface) and maps LocalFitSettings onto
// IcpSettings; the terms, the solve and the stop test are the engine's.
//
// Degeneracy: a flat flange fixes only its normal offset and its tilt; sliding in its plane
// and turning about its normal leave the error unchanged. The engine solves the 6x6 normal
// equations in the span of the eigenvectors whose eigenvalue is significant (rotation about
// the subset's centroid, scaled by its radius so both halves share a unit), and holds the
// other directions at zero motion. The result therefore never wanders along a direction the
// data cannot see, and `determined_directions` says how many directions were fitted.

#include <cstdint>
#include <vector>

#include "analysis/core/expected.hpp"
#include "analysis/core/kdtree.hpp"
#include "analysis/core/part_model.hpp"
#include "analysis/core/point_cloud.hpp"
#include "analysis/registration/icp.hpp"

namespace springscan::analysis {

/// Where a scan point finds its partner on the model.
enum class LocalFitCorrespondence {
  kModelSamples,  ///< nearest model sample, with its exact normal (fast; exact on flat faces)
  kExactSurface,  ///< PartModel::distance (exact foot on every face; slower)
};

/// Each field maps onto the IcpSettings field of the same name (ranges: IcpSettings).
struct LocalFitSettings {
  int max_iterations = 30;                      ///< ICP iterations (pair searches) at most
  int max_inner_iterations = 10;                ///< Gauss-Newton steps per set of pairs
  double max_correspondence_distance_mm = 5.0;  ///< pairs farther apart are left out
  double inlier_sigma_factor = 3.0;       ///< residuals beyond factor * 1.4826 * MAD are left out
  double min_inlier_threshold_mm = 0.01;  ///< that residual threshold never goes below this
  double degenerate_eigenvalue_ratio = 1e-4;  ///< directions below ratio * largest are held
  double convergence_rotation_deg = 1e-5;     ///< converged when an update on fresh pairs
                                              ///< turns less than this ...
  double convergence_translation_mm = 1e-5;   ///< ... and moves less than this
  int min_points = 50;                        ///< smaller subsets are an error, >= 3
  LocalFitCorrespondence correspondence = LocalFitCorrespondence::kModelSamples;  ///< see enum
  int threads = 0;  ///< worker threads, 0 = all cores; the result does not depend on it
};

/// The whole model prepared for local fits: a k-d tree over its samples. Build it once and
/// share it between fits. Holds a reference: `model` must outlive the target. Immutable after
/// construction, so concurrent fits may share it.
class LocalFitTarget {
 public:
  explicit LocalFitTarget(const PartModel& model);
  const PartModel& model() const { return *model_; }
  const KdTree& tree() const { return tree_; }
  /// The model is a solid sheet (a flange has two skins): pairs follow the facing rule.
  bool two_skins() const { return two_skins_; }
  /// The thinnest flange's thickness (0 for a surface model): how far apart the two skins are.
  double sheet_thickness_mm() const { return sheet_thickness_mm_; }

 private:
  const PartModel* model_;
  KdTree tree_;
  bool two_skins_ = false;
  double sheet_thickness_mm_ = 0.0;
};

struct LocalFitResult {
  Transform T_model_subset = Transform::Identity();  ///< maps the subset onto the model
  double rms_mm = 0.0;                ///< rms point-to-plane residual of the inliers at the end
  std::size_t points = 0;             ///< subset size
  std::size_t inliers = 0;            ///< pairs used in the last iteration
  int iterations = 0;                 ///< pair searches
  bool converged = false;             ///< fresh pairs moved the subset less than the settings
  std::vector<double> error_history;  ///< E(i) with the pairs of search i: mean squared
                                      ///< residual of the inliers, mm^2; when converged, last
                                      ///< E at the final transform
  int determined_directions = 0;      ///< of 6 in the last iteration; a flat flange gives 3
};

/// The engine's settings for a local fit: point-to-plane, no trimming or kernel (the residual
/// threshold rejects outliers), no error or ratio stop.
IcpSettings icp_settings(const LocalFitSettings& settings);

/// The settings' first out-of-range field, named as in LocalFitSettings, or nothing.
std::optional<Error> validate(const LocalFitSettings& settings,
                              std::string_view context = "local_fit: ");

/// Fits scan.points[indices] to the whole model, starting from the identity (the scan is
/// already in the CAD frame). Errors: invalid settings, fewer than min_points indices, an index out
/// of range, a model without sample normals, kExactSurface without PartModel::distance, or too few
/// correspondences within max_correspondence_distance_mm.
Expected<LocalFitResult> local_fit(const LocalFitTarget& target, const PointCloud& scan,
                                   const std::vector<std::uint32_t>& indices,
                                   const LocalFitSettings& settings = {});

/// Subset selection: the scan points inside an axis-aligned box (CAD frame, mm).
std::vector<std::uint32_t> points_in_box(const PointCloud& scan, const Eigen::AlignedBox3d& box);

/// Subset selection by CAD faces: the scan points whose nearest model sample (within
/// max_distance_mm) lies on one of `face_ids`.
std::vector<std::uint32_t> points_on_faces(const LocalFitTarget& target, const PointCloud& scan,
                                           const std::vector<int>& face_ids,
                                           double max_distance_mm = 5.0, int threads = 0);

}  // namespace springscan::analysis
