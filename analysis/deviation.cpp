#include "analysis/deviation.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "analysis/parallel.hpp"

namespace springscan::analysis {

Expected<DeviationResult> signed_deviation(const std::vector<Vec3>& scan_in_cad,
                                           const PartModel& model, const KdTree& model_tree,
                                           const DeviationSettings& settings) {
  if (!all_finite(scan_in_cad)) return fail("deviation: the scan has non-finite coordinates");
  if (!(settings.tolerance_mm > 0.0))
    return fail("deviation: tolerance_mm must be > 0, got " + std::to_string(settings.tolerance_mm));
  DeviationResult result;
  result.exact = model.distance != nullptr;
  if (!result.exact) {
    if (model_tree.empty()) return fail("deviation: the model has no samples");
    if (model.samples.normals.size() != model_tree.size())
      return fail("deviation: the model samples need one normal each (" +
                  std::to_string(model.samples.normals.size()) + " normals for " +
                  std::to_string(model_tree.size()) + " indexed samples)");
  }
  result.signed_distance_mm.resize(scan_in_cad.size());
  parallel_blocks(scan_in_cad.size(), settings.threads,
                  [&](std::size_t, std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      const Vec3& q = scan_in_cad[i];
      if (result.exact) {
        result.signed_distance_mm[i] = model.distance->closest(q).signed_distance_mm;
      } else {
        // Tangent plane of the nearest sample: exact on flat faces, and the sign says whether
        // the point lies above or below the surface (paper §3, Figure 7 colouring).
        const auto hit = model_tree.nearest(q);
        const Vec3& n = model.samples.normals[hit->index];
        result.signed_distance_mm[i] = n.dot(q - model_tree.points()[hit->index]);
      }
    }
  });
  result.statistics = deviation_statistics(result.signed_distance_mm, settings.tolerance_mm);
  return result;
}

DeviationStatistics deviation_statistics(const std::vector<double>& d, double tolerance_mm) {
  DeviationStatistics s;
  s.tolerance_mm = tolerance_mm;
  s.points = d.size();
  if (d.empty()) return s;
  struct Sums {
    double sum = 0.0, sum2 = 0.0;
    std::size_t out = 0;
  };
  std::vector<Sums> partial(block_count(d.size()));
  parallel_blocks(d.size(), 0, [&](std::size_t b, std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      partial[b].sum += d[i];
      partial[b].sum2 += d[i] * d[i];
      if (std::abs(d[i]) > tolerance_mm) ++partial[b].out;
    }
  });
  Sums total;
  for (const auto& p : partial) {  // block order: independent of the thread count
    total.sum += p.sum;
    total.sum2 += p.sum2;
    total.out += p.out;
  }
  const auto [lo, hi] = std::minmax_element(d.begin(), d.end());
  s.min_mm = *lo;
  s.max_mm = *hi;
  const auto n = static_cast<double>(d.size());
  s.mean_mm = total.sum / n;
  s.rms_mm = std::sqrt(total.sum2 / n);
  s.fraction_out_of_tolerance = static_cast<double>(total.out) / n;
  std::vector<double> magnitude(d.size());
  std::transform(d.begin(), d.end(), magnitude.begin(), [](double v) { return std::abs(v); });
  // Nearest rank: the smallest value with at least 95 % of the values at or below it.
  const auto rank = static_cast<std::size_t>(std::ceil(0.95 * n)) - 1;
  std::nth_element(magnitude.begin(), magnitude.begin() + static_cast<std::ptrdiff_t>(rank),
                   magnitude.end());
  s.p95_mm = magnitude[rank];
  return s;
}

Rgb deviation_color(double signed_distance_mm, double scale_mm) {
  const double t = scale_mm > 0.0 ? std::clamp(signed_distance_mm / scale_mm, -1.0, 1.0) : 0.0;
  const auto level = [](double x) { return static_cast<std::uint8_t>(std::lround(255.0 * x)); };
  if (!std::isfinite(t)) return {0, 0, 0};
  if (t < 0.0) return {0, level(1.0 + t), level(-t)};  // green -> blue
  return {level(t), level(1.0 - t), 0};                 // green -> red
}

}  // namespace springscan::analysis
