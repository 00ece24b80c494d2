#include "analysis/registration/orientation_settle.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <sstream>

#include "analysis/core/parallel.hpp"
#include "analysis/core/spatial_order.hpp"
#include "analysis/registration/facing.hpp"

namespace springscan::analysis {
namespace {

constexpr double kDegPerRad = 180.0 / 3.14159265358979323846;
constexpr char kAmbiguousWarning[] = "global fit: the orientation is ambiguous";

double rotation_apart_deg(const Transform& a, const Transform& b) {
  return Eigen::AngleAxisd(a.linear() * b.linear().transpose()).angle() * kDegPerRad;
}

// The best-scoring candidate of each distinct orientation, other than the best's, that scored
// within settle_ratio of the best and is no symmetry of the model away from it.
std::vector<std::size_t> rivals_of(const OrientationChoice& choice, const GlobalFitSettings& s) {
  const auto& cs = choice.candidates;
  const OrientationCandidate& best = cs[choice.best];
  const double distinct = s.pca.distinct_pose_deg;
  std::vector<std::size_t> rivals;
  for (std::size_t i = 0; i < cs.size(); ++i) {
    if (i == choice.best || cs[i].equivalent ||
        rotation_apart_deg(cs[i].T_cad_scan, best.T_cad_scan) <= distinct ||
        !(best.score_mm2 >= s.orientation.settle_ratio * cs[i].score_mm2))
      continue;
    auto same = std::find_if(rivals.begin(), rivals.end(), [&](std::size_t j) {
      return rotation_apart_deg(cs[i].T_cad_scan, cs[j].T_cad_scan) <= distinct;
    });
    if (same == rivals.end()) {
      rivals.push_back(i);
    } else if (cs[i].score_mm2 < cs[*same].score_mm2) {
      *same = i;
    }
  }
  return rivals;
}

// One orientation taken as far as the global fit took the best, and judged.
struct Settled {
  std::size_t candidate = 0;
  IcpResult icp;
  BoundaryResult boundary;
  double whole_mm2 = 0.0;           // exact score of the fit points
  std::size_t feature_points = 0;   // scan points judged in the symmetry features
  std::size_t feature_misfits = 0;  // ... that lie off the surface beyond the noise
  std::vector<double> decisive_mm;  // |exact distance| of each decisive point (NaN: none)
};

// |exact distance| of every point under T. Queried in space order (closest_in_order: each
// query starts from its neighbour's answer), whatever the scan's order; the answers are the same.
std::vector<double> exact_distances(const std::vector<Vec3>& points, const Transform& T,
                                    const SurfaceDistance& exact) {
  const std::vector<std::uint32_t> order = search_order(points, 1);
  std::vector<Vec3> ordered(points.size());
  for (std::size_t k = 0; k < order.size(); ++k) ordered[k] = T * points[order[k]];
  std::vector<double> d(points.size());
  closest_in_order(
      exact, 0, ordered.size(), [&](std::size_t k) { return ordered[k]; },
      [&](std::size_t k, const SurfaceHit& hit) {
        d[order[k]] = std::abs(hit.signed_distance_mm);
      });
  return d;
}

// The decisive points' verdict. Two orientations of a near-symmetric part put its surface in
// nearly the same place: a scan point lies about as far off the one as off the other, its noise
// and its flange's springback alike, and only where the part is not symmetric (a notch, a hole,
// a tab the other orientation lacks) does one of them leave it much farther off. Such a point
// tells against that orientation: farther by decisive_margin_mm (or decisive_sigmas robust
// sigmas of all points' differences, how far apart the two fits lie) and decisive_far_ratio
// times as far. The ratio keeps out the points both leave off the surface: a springback-turned
// flange that the two fits spread differently (the side panel's bend lines, 0.23 against
// 0.13 mm, told against its right orientation before it). The evidence is weighed by how much
// farther (up to decisive_cap_mm): a notch's points lie millimetres off under the wrong
// orientation, an outlier or a rim point that happens to qualify a few tenths.
struct DecisiveCounts {
  std::vector<std::vector<std::size_t>> against;  // [a][b]: points a fits and b leaves off
  std::vector<std::vector<double>> excess_mm;     // [a][b]: their summed excess, capped
  double margin_mm = 0.0;                         // the largest margin of a pair
};

// 1.4826 x the median of |values| (non-finite ones left out); 0 for none.
double robust_sigma(std::vector<double> d) {
  std::erase_if(d, [](double v) { return !std::isfinite(v); });
  for (double& v : d) v = std::abs(v);
  if (d.empty()) return 0.0;
  const auto mid = d.begin() + static_cast<std::ptrdiff_t>(d.size() / 2);
  std::nth_element(d.begin(), mid, d.end());
  return 1.4826 * *mid;
}

// The points among `candidates` (indices into `points`) with another of them within
// `company_mm`: a notch or hole shows as a patch of points that one orientation leaves off the
// surface, an outlier as a lone one.
std::vector<std::size_t> in_company(const std::vector<std::size_t>& candidates,
                                    const std::vector<Vec3>& points, double company_mm) {
  if (!(company_mm > 0.0)) return candidates;
  std::vector<Vec3> at;
  at.reserve(candidates.size());
  for (std::size_t i : candidates) at.push_back(points[i]);
  const KdTree tree(at);
  std::vector<Neighbor> near;
  std::vector<std::size_t> kept;
  for (std::size_t k = 0; k < candidates.size(); ++k) {
    tree.radius(at[k], company_mm, near);
    if (near.size() > 1) kept.push_back(candidates[k]);
  }
  return kept;
}

// `points`: the decisive points (one per entry of every Settled::decisive_mm).
DecisiveCounts count_decisive(const std::vector<Settled>& all, const OrientationSettings& s,
                              const std::vector<Vec3>& points) {
  const std::size_t n = all.size();
  DecisiveCounts out{std::vector<std::vector<std::size_t>>(n, std::vector<std::size_t>(n, 0)),
                     std::vector<std::vector<double>>(n, std::vector<double>(n, 0.0)), 0.0};
  const auto tells = [&](double d_a, double d_b, double margin) {
    return d_b - d_a > margin && d_b > s.decisive_far_ratio * d_a;
  };
  const auto add = [&](std::size_t a, std::size_t b, const std::vector<std::size_t>& told) {
    const std::vector<double>&da = all[a].decisive_mm, &db = all[b].decisive_mm;
    for (std::size_t i : in_company(told, points, s.decisive_company_mm)) {
      ++out.against[a][b];
      out.excess_mm[a][b] += std::min(db[i] - da[i], s.decisive_cap_mm);
    }
  };
  for (std::size_t a = 0; a < n; ++a)
    for (std::size_t b = a + 1; b < n; ++b) {
      const std::vector<double>&da = all[a].decisive_mm, &db = all[b].decisive_mm;
      std::vector<double> diff(da.size());
      for (std::size_t i = 0; i < da.size(); ++i) diff[i] = db[i] - da[i];
      const double margin =
          std::max(s.decisive_margin_mm, s.decisive_sigmas * robust_sigma(std::move(diff)));
      out.margin_mm = std::max(out.margin_mm, margin);
      std::vector<std::size_t> against_b, against_a;
      for (std::size_t i = 0; i < da.size(); ++i) {
        if (tells(da[i], db[i], margin)) against_b.push_back(i);
        if (tells(db[i], da[i], margin)) against_a.push_back(i);
      }
      add(a, b, against_b);
      add(b, a, against_a);
    }
  return out;
}

// The orientation that at least min_decisive_points favour over every other, with at most
// decisive_ratio of that evidence for the other.
std::optional<std::size_t> decisive_winner(const DecisiveCounts& c, const OrientationSettings& s) {
  const std::size_t n = c.against.size();
  for (std::size_t w = 0; w < n; ++w) {
    bool wins = true;
    for (std::size_t k = 0; k < n && wins; ++k)
      wins = k == w || (c.against[w][k] >= s.min_decisive_points &&
                        c.excess_mm[k][w] <= s.decisive_ratio * c.excess_mm[w][k]);
    if (wins) return w;
  }
  return std::nullopt;
}

// The scan points that land in a symmetry feature under T (CAD frame), at most `count` of them
// evenly strided.
std::vector<Vec3> in_features(const std::vector<Vec3>& scan, const Transform& T,
                              const std::vector<SymmetryFeature>& features, std::size_t count) {
  std::vector<Vec3> inside;
  for (const Vec3& p : scan) {
    const Vec3 q = T * p;
    for (const SymmetryFeature& f : features)
      if ((q - f.center).squaredNorm() <= f.radius_mm * f.radius_mm) {
        inside.push_back(q);
        break;
      }
  }
  return strided_sample(inside, count);
}

// The scan's noise as a fit sees it: a robust sigma of the exact distances.
double robust_sigma(const std::vector<Vec3>& points, const Transform& T,
                    const SurfaceDistance& exact) {
  std::vector<double> d(points.size());
  for (std::size_t i = 0; i < points.size(); ++i)
    d[i] = std::abs(exact.closest(T * points[i]).signed_distance_mm);
  return robust_sigma(std::move(d));
}

// `decisive`: the scan points every orientation's distances are compared on.
void judge(const OrientationSettleInput& in, const FacingSample& sample,
           const std::vector<Vec3>& decisive, const OrientationSettings& s, Settled& out) {
  const SurfaceDistance& exact = *in.model.distance;
  const Transform& T = out.boundary.T_cad_scan;
  out.whole_mm2 = exact_surface_score(sample.points, sample.normals, T, exact, s.score_cap_mm);
  out.decisive_mm = exact_distances(decisive, T, exact);
  if (s.symmetry_features.empty()) return;
  // A misfit stands out of this fit's own noise, whatever the scanner's.
  const double misfit_mm = std::max(
      s.feature_misfit_mm, s.feature_misfit_sigmas * robust_sigma(sample.points, T, exact));
  const std::vector<Vec3> points = in_features(in.scan, T, s.symmetry_features, s.feature_points);
  out.feature_points = points.size();
  for (const Vec3& q : points)
    out.feature_misfits += std::abs(exact.closest(q).signed_distance_mm) >= misfit_mm;
}

// The features' verdict: the orientation with the fewest misfits in them, when it has clearly
// fewer than every other (a hole of the model that the other orientation fills with scan points,
// a tab it leaves bare); nothing when they cannot tell. A feature whose content the scan shows
// alike under both orientations gives both the same few misfits, and then it does not decide,
// whatever the fits' small differences in quality.
std::optional<std::size_t> feature_winner(const std::vector<Settled>& all,
                                          const OrientationSettings& s) {
  std::size_t w = 0;
  for (std::size_t k = 1; k < all.size(); ++k)
    if (all[k].feature_misfits < all[w].feature_misfits) w = k;
  for (std::size_t k = 0; k < all.size(); ++k) {
    if (k == w) continue;
    const std::size_t lo = all[w].feature_misfits, hi = all[k].feature_misfits;
    if (hi < lo + s.min_feature_misfits || 2 * lo > hi) return std::nullopt;
  }
  return w;
}

// The lowest score wins (the first, the global fit's best, on ties); returns winner / the next
// lowest (0 when that is 0 too: a tie at no error is ambiguous), and sets `winner`.
double rank(const std::vector<Settled>& all, double Settled::*score, std::size_t& winner) {
  winner = 0;
  for (std::size_t k = 1; k < all.size(); ++k)
    if (all[k].*score < all[winner].*score) winner = k;
  double next = std::numeric_limits<double>::infinity();
  for (std::size_t k = 0; k < all.size(); ++k)
    if (k != winner) next = std::min(next, all[k].*score);
  return next > 0.0 ? all[winner].*score / next : 1.0;
}

// The settled orientations judged, in order: the symmetry features when they tell them apart;
// else the decisive points of the whole scan; else the converged surface scores, which within
// noise of each other cannot overturn the global fit's choice (the part is ambiguous then,
// whichever is kept: with springback both errors are mostly the flanges' turn, and their order
// a matter of where each fit spread it). Sets choice.ambiguity and decided_by; returns the
// winner's index in `all`.
std::size_t decide(const std::vector<Settled>& all, const std::vector<Vec3>& decisive,
                   const GlobalFitSettings& settings, OrientationChoice& choice,
                   std::vector<std::string>& warnings) {
  const OrientationSettings& os = settings.orientation;
  if (!os.symmetry_features.empty()) {
    if (const auto by_features = feature_winner(all, os)) {
      std::size_t fewest_other = std::numeric_limits<std::size_t>::max();
      for (std::size_t k = 0; k < all.size(); ++k)
        if (k != *by_features) fewest_other = std::min(fewest_other, all[k].feature_misfits);
      choice.ambiguity = static_cast<double>(all[*by_features].feature_misfits + 1) /
                         static_cast<double>(fewest_other + 1);
      choice.decided_by = "symmetry features";
      return *by_features;
    }
    std::ostringstream text;
    text << "global fit: the symmetry features do not tell the orientations apart in this scan "
            "(points off the surface beyond the noise:";
    for (const Settled& r : all) text << " " << r.feature_misfits << " of " << r.feature_points;
    text << "): the whole part decides";
    warnings.push_back(text.str());
  }
  const DecisiveCounts counts = count_decisive(all, os, decisive);
  if (const auto by_points = decisive_winner(counts, os)) {
    double worst = 0.0;
    for (std::size_t k = 0; k < all.size(); ++k)
      if (k != *by_points)
        worst = std::max(worst, (counts.excess_mm[k][*by_points] + counts.margin_mm) /
                                    (counts.excess_mm[*by_points][k] + counts.margin_mm));
    choice.ambiguity = worst;
    choice.decided_by = "decisive points";
    return *by_points;
  }
  std::size_t winner = 0;
  choice.ambiguity = rank(all, &Settled::whole_mm2, winner);
  choice.decided_by = "converged surface";
  if (choice.ambiguity > settings.symmetry_warning_ratio) {
    winner = 0;
    std::ostringstream text;
    text << "global fit: no scan point tells the orientations apart (points more than "
         << counts.margin_mm << " mm farther off the surface under one than under another:";
    for (std::size_t a = 0; a < all.size(); ++a)
      for (std::size_t b = 0; b < all.size(); ++b)
        if (a != b) text << " " << counts.against[a][b];
    text << "): the part's distinguishing features are not in the scan";
    warnings.push_back(text.str());
  }
  return winner;
}

void restate_ambiguity(GlobalFitResult& fit) {
  auto& w = fit.warnings;
  w.erase(
      std::remove_if(w.begin(), w.end(),
                     [](const std::string& text) { return text.starts_with(kAmbiguousWarning); }),
      w.end());
  if (!fit.ambiguous) return;
  std::ostringstream text;
  text << kAmbiguousWarning << ": two distinct orientations fit within noise of each other ("
       << fit.orientation.decided_by << ", robust error ratio " << fit.orientation.ambiguity << ")";
  if (fit.orientation.decided_by != "symmetry features")
    text << "; a part catalogue entry can name the feature that breaks the symmetry "
            "(registration.symmetry_features)";
  w.push_back(text.str());
}

}  // namespace

Expected<BoundaryResult> settle_orientation(const OrientationSettleInput& in,
                                            const GlobalFitSettings& settings, GlobalFitResult& fit,
                                            BoundaryResult pinned) {
  OrientationChoice& choice = fit.orientation;
  if (!in.model.distance || choice.candidates.size() < 2) return pinned;
  const std::vector<std::size_t> rivals = rivals_of(choice, settings);
  if (rivals.empty()) return pinned;
  // all[0]: the best as the pipeline has it; then each rival taken as far, in parallel.
  std::vector<Settled> all(rivals.size() + 1);
  all[0].candidate = choice.best;
  all[0].icp = fit.icp;
  all[0].boundary = std::move(pinned);
  std::vector<std::string> errors(all.size());
  const FacingSample sample =
      facing_sample(in.fit_points, in.fit_normals, settings.orientation.score_points);
  const std::vector<Vec3> decisive = strided_sample(in.scan, settings.orientation.decisive_points);
  // The rivals taken as far one after another, each on every thread (a fit's result does not
  // depend on its thread count), then every orientation judged in parallel. Over the rivals in
  // parallel, a single rival's fit ran on one thread while the other judged the best (a short
  // task) and then sat idle.
  for (std::size_t k = 1; k < all.size(); ++k) {
    Settled& r = all[k];
    r.candidate = rivals[k - 1];
    auto icp_fit = final_icp(in.fit_points, in.model_tree, in.model.samples.normals,
                             choice.candidates[r.candidate].T_cad_scan, settings, in.fit_normals);
    if (!icp_fit) {
      errors[k] = icp_fit.message();
      continue;
    }
    if (auto e = finish_best_fit(in.exact_points, in.exact_normals, in.exact_updates, in.model_tree,
                                 in.model.samples.normals, settings,
                                 in.exact_updates ? settings.exact_iterations : 0,
                                 settings.icp.trimmed_fraction, *icp_fit)) {
      errors[k] = e->message;
      continue;
    }
    auto pin = in.boundary_scan ? pin_to_boundary(*in.boundary_scan, icp_fit->T_target_source,
                                                  in.model, in.model_tree, settings.boundary)
                                : pin_to_boundary(in.scan, icp_fit->T_target_source, in.model,
                                                  in.model_tree, settings.boundary);
    if (!pin) {
      errors[k] = pin.message();
      continue;
    }
    r.icp = std::move(*icp_fit);
    r.boundary = std::move(*pin);
  }
  for (const std::string& e : errors)
    if (!e.empty()) return fail("global fit: settling the orientation: " + e);
  parallel_tasks(all.size(), settings.icp.threads,
                 [&](std::size_t k) { judge(in, sample, decisive, settings.orientation, all[k]); });
  const std::size_t winner = decide(all, decisive, settings, choice, fit.warnings);
  for (const Settled& r : all) choice.candidates[r.candidate].score_mm2 = r.whole_mm2;
  const Settled& w = all[winner];
  if (winner > 0) {
    fit.icp = w.icp;
    fit.T_cad_scan = w.boundary.T_cad_scan;
    fit.rms_final_mm = rms_nearest_distance(in.fit_points, fit.T_cad_scan, in.model_tree,
                                            settings.icp.trimmed_fraction, settings.icp.threads);
  }
  choice.best = w.candidate;
  choice.ambiguous = choice.ambiguity > settings.symmetry_warning_ratio;
  fit.ambiguous = choice.ambiguous;
  restate_ambiguity(fit);
  return std::move(all[winner].boundary);
}

}  // namespace springscan::analysis
