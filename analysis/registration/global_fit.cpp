#include "analysis/registration/global_fit.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <sstream>

#include "analysis/core/parallel.hpp"
#include "analysis/preprocess/reduction.hpp"
#include "analysis/preprocess/voxel.hpp"
#include "analysis/registration/facing.hpp"

namespace springscan::analysis {
namespace {

// The coarse model stands in for the full one in the candidate scores only when it keeps the
// part's shape: at least this many voxels (the screening round samples 250 scan points) ...
constexpr std::size_t kMinCoarseModelPoints = 100;
// ... and when it is small enough to pay for its own k-d tree: at most this share of the samples.
constexpr double kMaxCoarseModelShare = 0.5;
// A scan whose least principal variance is below this share of its largest is flat: only its
// outline fixes the in-plane placement.
constexpr double kFlatEigenvalueRatio = 1e-8;

struct CoarseModel {
  std::unique_ptr<KdTree> tree;  // null: use the full model
  std::vector<Vec3> normals;
};

// The coarse model: one point per voxel, so many as the voxel reduction keeps. Its points are
// voxel centroids with averaged normals, except under the facing rule: a voxel of a solid holds
// both skins, whose normals cancel, so the samples themselves are kept there (evenly strided).
CoarseModel coarse_model(const KdTree& tree, const std::vector<Vec3>& normals, double divisions,
                         bool facing) {
  CoarseModel out;
  if (!(divisions > 0.0) || normals.size() != tree.size()) return out;
  PointCloud cloud{tree.points(), normals, {}, {}, {}};
  const auto [lo, hi] = bounding_box(cloud.points);
  const double voxel = (hi - lo).norm() / divisions;
  if (!(voxel > 0.0)) return out;
  auto reduced = voxel_reduce(cloud, {voxel});
  if (!reduced || reduced->cloud.size() < kMinCoarseModelPoints ||
      static_cast<double>(reduced->cloud.size()) >
          kMaxCoarseModelShare * static_cast<double>(tree.size()))
    return out;
  if (facing) {
    out.normals = strided_sample(normals, reduced->cloud.size());
    out.tree = std::make_unique<KdTree>(strided_sample(tree.points(), reduced->cloud.size()));
    return out;
  }
  out.normals = std::move(reduced->cloud.normals);
  out.tree = std::make_unique<KdTree>(std::move(reduced->cloud.points));
  return out;
}

// The fit's own settings (the ICP's are checked by icp()).
std::optional<Error> check_settings(const GlobalFitSettings& s) {
  if (!(s.symmetry_warning_ratio >= 0.0 && s.symmetry_warning_ratio <= 1.0))
    return fail("global fit: symmetry_warning_ratio = " + std::to_string(s.symmetry_warning_ratio) +
                ": must be in [0, 1]");
  if (!(s.pca.distinct_pose_deg >= 0.0 && s.pca.distinct_pose_deg <= 180.0))
    return fail("global fit: pca.distinct_pose_deg = " + std::to_string(s.pca.distinct_pose_deg) +
                ": must be in [0, 180]");
  return std::nullopt;
}

// The orientation comparison takes its ambiguity threshold and distinctness from the fit's.
OrientationSettings orientation_settings(const GlobalFitSettings& s) {
  OrientationSettings out = s.orientation;
  out.ambiguous_error_ratio = s.symmetry_warning_ratio;
  out.distinct_pose_deg = s.pca.distinct_pose_deg;
  return out;
}

// The rms before and after the PCA alignment are figures for the report, taken where the scan
// may still be far from the model: a nearest search from 300 mm away visits most of the tree,
// so a sample of the scan stands in for all of it.
constexpr std::size_t kDiagnosticSample = 4096;

}  // namespace

double rms_nearest_distance(const std::vector<Vec3>& points, const Transform& T, const KdTree& tree,
                            double trimmed_fraction, int threads) {
  if (points.empty() || tree.empty()) return 0.0;
  std::vector<double> d2(points.size());
  parallel_blocks(points.size(), threads, [&](std::size_t, std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) d2[i] = tree.nearest(T * points[i])->squared_distance;
  });
  const auto drop = static_cast<std::size_t>(
      std::clamp(trimmed_fraction, 0.0, kMaxTrimmedFraction) * static_cast<double>(d2.size()));
  const auto keep = d2.size() - drop;
  if (drop > 0)
    std::nth_element(d2.begin(), d2.begin() + static_cast<std::ptrdiff_t>(keep - 1), d2.end());
  double sum = 0.0;
  for (std::size_t i = 0; i < keep; ++i) sum += d2[i];  // the kept values in a fixed order
  return std::sqrt(sum / static_cast<double>(keep));
}

Expected<IcpResult> final_icp(const std::vector<Vec3>& scan, const KdTree& model_tree,
                              const std::vector<Vec3>& model_normals, const Transform& start,
                              const GlobalFitSettings& settings,
                              const std::vector<Vec3>& scan_normals) {
  if (scan_normals.empty()) return icp(scan, model_tree, model_normals, start, settings.icp);
  return icp(scan,
             nearest_facing_pairs(model_tree, model_normals, scan_normals,
                                  settings.icp.max_correspondence_distance_mm),
             start, settings.icp);
}

std::optional<Error> finish_best_fit(const std::vector<Vec3>& scan,
                                     const std::vector<Vec3>& scan_normals,
                                     const SurfaceDistance* exact, const KdTree& model_tree,
                                     const std::vector<Vec3>& model_normals,
                                     const GlobalFitSettings& settings, int iterations,
                                     double trimmed_fraction, IcpResult& fit) {
  if (iterations <= 0 || scan.empty()) return std::nullopt;
  GlobalFitSettings last = settings;
  last.icp.max_iterations = iterations;
  last.icp.trimmed_fraction = trimmed_fraction;
  auto more =
      exact
          ? icp(scan,
                exact_surface_pairs(*exact, scan_normals, last.icp.max_correspondence_distance_mm),
                fit.T_target_source, last.icp)
          : final_icp(scan, model_tree, model_normals, fit.T_target_source, last, scan_normals);
  if (!more)
    return more.error().prepend(exact ? "global fit: on the exact surface: "
                                      : "global fit: least-squares updates: ");
  fit.T_target_source = more->T_target_source;
  fit.iterations += more->iterations;
  // Its first entry is the error it started from, the last of `fit`'s own (on other pairs).
  if (!more->error_history.empty())
    fit.error_history.insert(fit.error_history.end(), more->error_history.begin() + 1,
                             more->error_history.end());
  fit.inliers = more->inliers;
  fit.converged = more->converged;
  fit.stop_reason = more->stop_reason + (exact ? " (on the exact surface)" : " (least squares)");
  return std::nullopt;
}

Expected<GlobalFitResult> global_fit(const std::vector<Vec3>& scan, const KdTree& model_tree,
                                     const std::vector<Vec3>& model_normals,
                                     const GlobalFitSettings& settings,
                                     const std::vector<Vec3>& scan_normals) {
  if (auto error = check_settings(settings)) return *error;
  if (scan.empty()) return fail("global fit: the scan is empty");
  if (model_tree.empty()) return fail("global fit: the model is empty");
  if (!all_finite(scan)) return fail("global fit: the scan has non-finite (NaN/inf) coordinates");
  const bool facing = !scan_normals.empty();
  if (facing && (scan_normals.size() != scan.size() || model_normals.size() != model_tree.size()))
    return fail("global fit: the facing rule needs one normal per scan and per model point (" +
                std::to_string(scan_normals.size()) + " for " + std::to_string(scan.size()) +
                " scan points)");
  GlobalFitResult result;
  const int threads = settings.icp.threads;
  const double trim = settings.icp.trimmed_fraction;
  const std::vector<Vec3> diagnostic = strided_sample(scan, kDiagnosticSample);
  result.rms_initial_mm =
      rms_nearest_distance(diagnostic, Transform::Identity(), model_tree, trim, threads);
  Transform start = Transform::Identity();
  if (settings.pca_initial_alignment) {
    PcaAlignSettings pca_settings = settings.pca;
    pca_settings.threads = threads;
    // The candidate search only has to tell poses apart: a coarse model makes its many short
    // ICP runs several times cheaper; the final ICP below uses the full model.
    const CoarseModel coarse =
        coarse_model(model_tree, model_normals, settings.pca_model_divisions, facing);
    auto pca = coarse.tree
                   ? pca_align(scan, *coarse.tree, coarse.normals, pca_settings, scan_normals)
                   : pca_align(scan, model_tree, model_normals, pca_settings, scan_normals);
    if (!pca) return pca.error().prepend("global fit: ");
    result.pca = std::move(*pca);
    result.rms_after_pca_mm =
        rms_nearest_distance(diagnostic, result.pca.T_pca, model_tree, trim, threads);
    // Every distinct finalist refined and scored on the same points against the full model.
    auto choice =
        choose_orientation(scan, model_tree, model_normals, result.pca.finalist_poses,
                           orientation_settings(settings), settings.icp, threads, scan_normals);
    if (!choice) return choice.error().prepend("global fit: ");
    result.orientation = std::move(*choice);
    start = result.orientation.candidates[result.orientation.best].T_cad_scan;
    result.ambiguous = result.orientation.ambiguous;
    if (result.ambiguous) {
      std::ostringstream text;
      text << "global fit: the orientation is ambiguous: two distinct orientations fit within "
              "noise of each other (robust error ratio "
           << result.orientation.ambiguity << ")";
      result.warnings.push_back(text.str());
    }
  } else {
    result.rms_after_pca_mm = result.rms_initial_mm;
  }
  auto fit = final_icp(scan, model_tree, model_normals, start, settings, scan_normals);
  if (!fit) return fit.error().prepend("global fit: ");
  result.icp = std::move(*fit);
  result.T_cad_scan = result.icp.T_target_source;
  result.rms_final_mm = rms_nearest_distance(scan, result.T_cad_scan, model_tree, trim, threads);
  // A flat scan fixes only its normal offset and tilt by the surface; in-plane placement then
  // rests on the outline (PCA) alone, even when ICP had nothing left to solve.
  const auto frame = principal_frame(scan);
  const bool flat = frame && frame->eigenvalues(2) <= kFlatEigenvalueRatio * frame->eigenvalues(0);
  if (result.icp.degenerate || flat)
    result.warnings.push_back(
        "global fit: the surface does not constrain every motion (e.g. a flat or cylindrical "
        "part); the fit along the free directions is arbitrary");
  if (!result.icp.converged)
    result.warnings.push_back("global fit: ICP did not converge (" + result.icp.stop_reason + ")");
  return result;
}

}  // namespace springscan::analysis
