#include "analysis/global_fit.hpp"

#include <cmath>
#include <sstream>

#include "analysis/parallel.hpp"

namespace springscan::analysis {

double rms_nearest_distance(const std::vector<Vec3>& points, const Transform& T,
                            const KdTree& tree, int threads) {
  if (points.empty() || tree.empty()) return 0.0;
  std::vector<double> partial(block_count(points.size()), 0.0);
  parallel_blocks(points.size(), threads, [&](std::size_t b, std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i)
      partial[b] += tree.nearest(T * points[i])->squared_distance;
  });
  double sum = 0.0;
  for (double p : partial) sum += p;  // block order: independent of the thread count
  return std::sqrt(sum / static_cast<double>(points.size()));
}

Expected<GlobalFitResult> global_fit(const std::vector<Vec3>& scan, const KdTree& model_tree,
                                     const std::vector<Vec3>& model_normals,
                                     const GlobalFitSettings& settings) {
  if (scan.empty()) return fail("global fit: the scan is empty");
  if (model_tree.empty()) return fail("global fit: the model is empty");
  if (!all_finite(scan)) return fail("global fit: the scan has non-finite (NaN/inf) coordinates");
  GlobalFitResult result;
  const int threads = settings.icp.threads;
  result.rms_initial_mm = rms_nearest_distance(scan, Transform::Identity(), model_tree, threads);
  Transform start = Transform::Identity();
  if (settings.pca_initial_alignment) {
    PcaAlignSettings pca_settings = settings.pca;
    pca_settings.threads = threads;
    auto pca = pca_align(scan, model_tree, model_normals, pca_settings);
    if (!pca) return fail("global fit: " + pca.message());
    result.pca = std::move(*pca);
    start = result.pca.T_target_source;
    result.rms_after_pca_mm = rms_nearest_distance(scan, result.pca.T_pca, model_tree, threads);
    if (result.pca.ambiguity > 0.9) {
      std::ostringstream text;
      text << "global fit: the part looks nearly symmetric (best/next distinct PCA candidate "
              "error ratio " << result.pca.ambiguity << "); the orientation may be ambiguous";
      result.warnings.push_back(text.str());
    }
  } else {
    result.rms_after_pca_mm = result.rms_initial_mm;
  }
  auto fit = icp(scan, model_tree, model_normals, start, settings.icp);
  if (!fit) return fail("global fit: " + fit.message());
  result.icp = std::move(*fit);
  result.T_cad_scan = result.icp.T_target_source;
  result.rms_final_mm = rms_nearest_distance(scan, result.T_cad_scan, model_tree, threads);
  // A flat scan fixes only its normal offset and tilt by the surface; in-plane placement then
  // rests on the outline (PCA) alone, even when ICP had nothing left to solve.
  const auto frame = principal_frame(scan);
  const bool flat = frame && frame->eigenvalues(2) <= 1e-8 * frame->eigenvalues(0);
  if (result.icp.degenerate || flat)
    result.warnings.push_back(
        "global fit: the surface does not constrain every motion (e.g. a flat or cylindrical "
        "part); the fit along the free directions is arbitrary");
  if (!result.icp.converged)
    result.warnings.push_back("global fit: ICP did not converge (" + result.icp.stop_reason + ")");
  return result;
}

}  // namespace springscan::analysis
