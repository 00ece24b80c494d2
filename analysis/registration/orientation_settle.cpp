#include "analysis/registration/orientation_settle.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <sstream>

#include "analysis/core/parallel.hpp"
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
};

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

// The scan's noise as a fit sees it: a robust sigma (1.4826 x the median) of the exact distances.
double robust_sigma(const std::vector<Vec3>& points, const Transform& T,
                    const SurfaceDistance& exact) {
  std::vector<double> d(points.size());
  for (std::size_t i = 0; i < points.size(); ++i)
    d[i] = std::abs(exact.closest(T * points[i]).signed_distance_mm);
  if (d.empty()) return 0.0;
  const auto mid = d.begin() + static_cast<std::ptrdiff_t>(d.size() / 2);
  std::nth_element(d.begin(), mid, d.end());
  return 1.4826 * *mid;
}

// `sample`: the fit points every orientation is scored on (the same for all).
void judge(const OrientationSettleInput& in, const FacingSample& sample,
           const OrientationSettings& s, Settled& out) {
  const SurfaceDistance& exact = *in.model.distance;
  const Transform& T = out.boundary.T_cad_scan;
  out.whole_mm2 = exact_surface_score(sample.points, sample.normals, T, exact, s.score_cap_mm);
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
  all[0] = {choice.best, fit.icp, std::move(pinned)};
  std::vector<std::string> errors(all.size());
  const FacingSample sample =
      facing_sample(in.fit_points, in.fit_normals, settings.orientation.score_points);
  parallel_tasks(all.size(), settings.icp.threads, [&](std::size_t k) {
    Settled& r = all[k];
    if (k > 0) {
      r.candidate = rivals[k - 1];
      GlobalFitSettings serial = settings;
      serial.icp.threads = 1;  // parallel over the rivals instead
      auto icp_fit = final_icp(in.fit_points, in.model_tree, in.model.samples.normals,
                               choice.candidates[r.candidate].T_cad_scan, serial, in.fit_normals);
      if (!icp_fit) {
        errors[k] = icp_fit.message();
        return;
      }
      if (auto e = finish_on_exact_surface(in.scan, in.scan_normals, in.exact_updates, serial,
                                           *icp_fit)) {
        errors[k] = e->message;
        return;
      }
      auto pin = pin_to_boundary(in.scan, icp_fit->T_target_source, in.model, in.model_tree,
                                 settings.boundary);
      if (!pin) {
        errors[k] = pin.message();
        return;
      }
      r.icp = std::move(*icp_fit);
      r.boundary = std::move(*pin);
    }
    judge(in, sample, settings.orientation, r);
  });
  for (const std::string& e : errors)
    if (!e.empty()) return fail("global fit: settling the orientation: " + e);
  // The features judge when they tell the orientations apart; else the whole part.
  const OrientationSettings& os = settings.orientation;
  std::size_t winner = 0;
  const auto by_features = os.symmetry_features.empty() ? std::nullopt : feature_winner(all, os);
  if (by_features) {
    winner = *by_features;
    std::size_t fewest_other = std::numeric_limits<std::size_t>::max();
    for (std::size_t k = 0; k < all.size(); ++k)
      if (k != winner) fewest_other = std::min(fewest_other, all[k].feature_misfits);
    choice.ambiguity = static_cast<double>(all[winner].feature_misfits + 1) /
                       static_cast<double>(fewest_other + 1);
    choice.decided_by = "symmetry features";
  } else {
    choice.ambiguity = rank(all, &Settled::whole_mm2, winner);
    // Within noise of each other the fits cannot overturn the global fit's choice (the part is
    // ambiguous then, whichever is kept): with springback both errors are mostly the flanges'
    // turn, and their order a matter of where each fit spread it.
    if (choice.ambiguity > settings.symmetry_warning_ratio) winner = 0;
    choice.decided_by = "converged surface";
    if (!os.symmetry_features.empty()) {
      std::ostringstream text;
      text << "global fit: the symmetry features do not tell the orientations apart in this scan "
              "(points off the surface beyond the noise:";
      for (const Settled& r : all) text << " " << r.feature_misfits << " of " << r.feature_points;
      text << "): the whole part decides";
      fit.warnings.push_back(text.str());
    }
  }
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
