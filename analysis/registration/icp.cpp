#include "analysis/registration/icp.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

#include "analysis/core/parallel.hpp"
#include "analysis/core/spatial_order.hpp"
#include "analysis/registration/icp_terms.hpp"

namespace springscan::analysis {
namespace {

using icp_terms::Partial;
using icp_terms::StepFrame;

constexpr double kRadPerDeg = std::numbers::pi / 180.0;
// The rotation scale of a source whose points all coincide: any positive length keeps the
// scaled system finite (such a source fixes no rotation anyway).
constexpr double kMinRotationScaleMm = 1e-9;

// Everything one run iterates over; the buffers are allocated once per run.
struct Run {
  const std::vector<Vec3>& source;
  const IcpPairSearch& search;
  const IcpSettings& s;
  Vec3 centroid = Vec3::Zero();
  double scale_mm = 1.0;  // rms distance of the source points from their centroid
  std::size_t min_pairs = 0;
  std::vector<std::uint32_t> order;  // the source in space order (find_pairs)
  std::vector<IcpPair> pairs;
  std::vector<double> residuals;
  std::vector<double> scratch;

  Run(const std::vector<Vec3>& points, const IcpPairSearch& finder, const IcpSettings& settings)
      : source(points),
        search(finder),
        s(settings),
        order(search_order(points, settings.threads)),
        pairs(points.size()) {
    for (const Vec3& p : source) centroid += p;
    centroid /= static_cast<double>(source.size());
    double spread = 0.0;
    for (const Vec3& p : source) spread += (p - centroid).squaredNorm();
    scale_mm =
        std::max(std::sqrt(spread / static_cast<double>(source.size())), kMinRotationScaleMm);
    const int unknowns = s.method == IcpMethod::kPointToPlane ? 6 : 3;
    min_pairs = static_cast<std::size_t>(s.min_pairs > 0 ? s.min_pairs : unknowns);
    if (s.inlier_sigma_factor > 0.0) residuals.resize(source.size());
    scratch.reserve(source.size());
  }

  // The pairs of every source point at T, searched in space order (spatial_order: neighbouring
  // searches walk the same part of the target's tree or BVH, whatever order the source came
  // in); each search writes its own pair, so the pairs are those of a search in index order.
  void find_pairs(const Transform& T) {
    parallel_blocks(source.size(), s.threads, [&](std::size_t, std::size_t begin, std::size_t end) {
      for (std::size_t k = begin; k < end; ++k) search(source, T, order[k], order[k] + 1, pairs);
    });
  }

  // The sums of the pairs kept at T (the current pairs, thresholds at T).
  Partial evaluate(const Transform& T, StepFrame& frame) {
    frame = {T * centroid, scale_mm};
    const icp_terms::Keep keep =
        icp_terms::keep_thresholds(source, T, pairs, s, residuals, scratch);
    return icp_terms::reduce(source, T, pairs, frame, keep, s);
  }
};

// The one stop test, on the evaluation `sums` of pair set i (after_negligible: the evaluation
// at the end, after an update on fresh pairs below the convergence tolerances). Records E.
std::optional<IcpStop> stop_test(const Partial& sums, int i, bool after_negligible, const Run& run,
                                 IcpResult& result) {
  result.inliers = sums.count;
  if (sums.count < run.min_pairs) return IcpStop::kTooFewPairs;
  const double E = sums.sum_e / static_cast<double>(sums.count);
  result.error_history.push_back(E);
  if (after_negligible) return IcpStop::kIncrement;
  if (run.s.min_error_mm > 0.0 && std::sqrt(E) <= run.s.min_error_mm) return IcpStop::kError;
  // Paper Figure 6b: E(i)/E(i-1) near 1 means no further progress. A rise counts too: with
  // trimming, the kept set can flip between two near-equal states at the noise floor.
  const auto& history = result.error_history;
  const double previous = i > 1 ? history[history.size() - 2] : 0.0;
  if (run.s.error_ratio_stop > 0.0 && previous > 0.0 && E / previous > run.s.error_ratio_stop)
    return IcpStop::kRatio;
  if (i >= run.s.max_iterations) return IcpStop::kIterations;
  return std::nullopt;
}

// How solving one set of pairs ended. kNegligible: its first update was below the tolerances,
// i.e. fresh pairs no longer move the source (converged).
enum class PairSet { kMoved, kNegligible, kTooFewPairs, kNumericalFailure };

// Up to max_inner_iterations updates on the current pairs, the first from `sums`.
PairSet solve_pair_set(Run& run, Partial sums, StepFrame frame, IcpResult& result) {
  ++result.iterations;
  Transform& T = result.T_target_source;
  for (int inner = 0; inner < run.s.max_inner_iterations; ++inner) {
    if (inner > 0) {
      sums = run.evaluate(T, frame);
      result.inliers = sums.count;
      if (sums.count < run.min_pairs) return PairSet::kTooFewPairs;
    }
    const icp_terms::Step step = icp_terms::solve(sums, frame, run.s);
    if (!step.motion.matrix().allFinite()) return PairSet::kNumericalFailure;
    T = step.motion * T;
    ++result.updates;
    result.determined_directions = step.determined_directions;
    result.degenerate = result.degenerate || step.determined_directions < 6;
    if (step.angle_rad < run.s.convergence_rotation_deg * kRadPerDeg &&
        step.translation_mm < run.s.convergence_translation_mm)
      return inner == 0 ? PairSet::kNegligible : PairSet::kMoved;
  }
  return PairSet::kMoved;
}

IcpResult& finish(IcpResult& result, IcpStop stop) {
  result.stop = stop;
  result.converged =
      stop == IcpStop::kIncrement || stop == IcpStop::kError || stop == IcpStop::kRatio;
  result.stop_reason = std::string(to_string(stop));
  if (stop == IcpStop::kTooFewPairs)
    result.stop_reason += " (" + std::to_string(result.inliers) + ")";
  return result;
}

std::optional<Error> check_inputs(const std::vector<Vec3>& source, const KdTree& target,
                                  const std::vector<Vec3>& normals, const IcpSettings& s) {
  if (source.empty()) return fail("icp: the source cloud is empty");
  if (target.empty()) return fail("icp: the target cloud is empty");
  if (!all_finite(source) || !all_finite(target.points()))
    return fail("icp: input has non-finite (NaN/inf) coordinates");
  if (s.method == IcpMethod::kPointToPlane && normals.size() != target.size())
    return fail("icp: point-to-plane needs one target normal per point, got " +
                std::to_string(normals.size()) + " for " + std::to_string(target.size()));
  return std::nullopt;
}

}  // namespace

std::string_view to_string(IcpStop stop) {
  constexpr std::string_view kNames[] = {"increment",  "error",         "ratio",
                                         "iterations", "too few pairs", "numerical failure"};
  return kNames[static_cast<std::size_t>(stop)];  // in the order of the enum
}

double IcpResult::rms_mm() const {
  return error_history.empty() ? 0.0 : std::sqrt(std::max(error_history.back(), 0.0));
}

IcpPairSearch nearest_point_pairs(const KdTree& tree, const std::vector<Vec3>& normals,
                                  double max_distance_mm) {
  const double limit =
      max_distance_mm > 0.0 ? max_distance_mm : std::numeric_limits<double>::infinity();
  const bool with_normals = normals.size() == tree.size();
  return [&tree, &normals, limit, with_normals](const std::vector<Vec3>& source, const Transform& T,
                                                std::size_t begin, std::size_t end,
                                                std::vector<IcpPair>& pairs) {
    for (std::size_t i = begin; i < end; ++i) {
      const Vec3 q = T * source[i];
      IcpPair& p = pairs[i];
      // The point's partner at the previous pose (a tree point) bounds the search: the nearest
      // lies no farther. The bound only prunes: the search still meets the points at the least
      // distance in the same order and keeps the first, so the pair is the same.
      double bound = limit;
      if (p.valid) {
        const double d2 = (q - p.point).squaredNorm();
        if (d2 > 0.0) bound = std::min(limit, std::sqrt(d2) * (1.0 + 1e-9));
      }
      const auto hit = tree.nearest(q, bound);
      p.valid = hit.has_value();
      if (!hit) continue;
      p.point = tree.points()[hit->index];
      if (with_normals) p.normal = normals[hit->index];
      p.squared_distance_mm2 = hit->squared_distance;
    }
  };
}

Expected<IcpResult> icp(const std::vector<Vec3>& source, const IcpPairSearch& search,
                        const Transform& initial, const IcpSettings& s) {
  if (auto error = validate(s)) return *error;
  if (source.empty()) return fail("icp: the source cloud is empty");
  Run run(source, search, s);
  IcpResult result;
  result.T_target_source = initial;
  for (int i = 0;; ++i) {
    // Pair, evaluate E(i) and test; then solve on these pairs until they stop moving.
    run.find_pairs(result.T_target_source);
    StepFrame frame;
    Partial sums = run.evaluate(result.T_target_source, frame);
    if (auto stop = stop_test(sums, i, false, run, result)) return finish(result, *stop);
    const PairSet outcome = solve_pair_set(run, sums, frame, result);
    if (outcome == PairSet::kTooFewPairs) return finish(result, IcpStop::kTooFewPairs);
    if (outcome == PairSet::kNumericalFailure) return finish(result, IcpStop::kNumericalFailure);
    if (outcome == PairSet::kNegligible) {
      // Converged: E at the final transform, on the same pairs (a negligible update cannot
      // change them), so that the history ends where the result is.
      sums = run.evaluate(result.T_target_source, frame);
      return finish(result, *stop_test(sums, i + 1, true, run, result));
    }
  }
}

Expected<IcpResult> icp(const std::vector<Vec3>& source, const KdTree& target,
                        const std::vector<Vec3>& target_normals, const Transform& initial,
                        const IcpSettings& s) {
  if (auto error = validate(s)) return *error;
  if (auto error = check_inputs(source, target, target_normals, s)) return *error;
  return icp(source, nearest_point_pairs(target, target_normals, s.max_correspondence_distance_mm),
             initial, s);
}

std::optional<Error> validate(const IcpSettings& s, std::string_view context) {
  struct Range {
    const char* field;
    double value, lo, hi;
  };
  const Range ranges[] = {
      {"max_iterations", double(s.max_iterations), 0, 10000},
      {"max_inner_iterations", double(s.max_inner_iterations), 1, 1000},
      {"max_correspondence_distance_mm", s.max_correspondence_distance_mm, 0, 1e9},
      {"trimmed_fraction", s.trimmed_fraction, 0, kMaxTrimmedFraction},
      {"inlier_sigma_factor", s.inlier_sigma_factor, 0, 100},
      {"min_inlier_threshold_mm", s.min_inlier_threshold_mm, 0, 1e9},
      {"kernel_scale_mm", s.kernel_scale_mm, 1e-9, 1e9},
      {"degenerate_eigenvalue_ratio", s.degenerate_eigenvalue_ratio, 0, 1},
      {"min_pairs", double(s.min_pairs), 0, 1e9},
      {"min_error_mm", s.min_error_mm, 0, 1e9},
      {"error_ratio_stop", s.error_ratio_stop, 0, 1},
      {"convergence_rotation_deg", s.convergence_rotation_deg, 0, 180},
      {"convergence_translation_mm", s.convergence_translation_mm, 0, 1e9},
      {"threads", double(s.threads), 0, 1024},
  };
  for (const Range& r : ranges) {
    if (std::isfinite(r.value) && r.value >= r.lo && r.value <= r.hi) continue;
    std::ostringstream text;
    text << context << r.field << " = " << r.value << ": must be in [" << r.lo << ", " << r.hi
         << "]";
    return fail(text.str());
  }
  return std::nullopt;
}

}  // namespace springscan::analysis
