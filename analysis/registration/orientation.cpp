#include "analysis/registration/orientation.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>

#include "analysis/core/parallel.hpp"
#include "analysis/core/spacing.hpp"
#include "analysis/registration/facing.hpp"

namespace springscan::analysis {
namespace {

constexpr double kRadPerDeg = 3.14159265358979323846 / 180.0;
// Model samples whose spacing is measured (evenly strided).
constexpr std::size_t kSpacingSamples = 256;
// A point's error is the least over this many nearest model samples.
constexpr std::size_t kScoreNeighbors = 4;
// Model samples moved onto the model to test two orientations for equivalence.
constexpr std::size_t kEquivalenceSamples = 1000;
// ... refined onto the model by at most this many ICP updates.
constexpr int kEquivalenceIterations = 30;

double rotation_apart_deg(const Transform& a, const Transform& b) {
  return Eigen::AngleAxisd(a.linear() * b.linear().transpose()).angle() / kRadPerDeg;
}

// A symmetric model fits the best orientation and the ones equivalent to it equally well: which
// of them scored lowest then depends on the points sampled, i.e. on the scan's point order (the
// demo hat, reversed, came out half turned with its bends numbered from the other end). The
// answer among them is the one nearest the nominal pose, the identity (the fixture holds the part
// near its CAD placement), ties to the lower index: the same for any point order, and the bends
// keep their CAD numbering (docs/alignment.md).
void take_nearest_nominal(OrientationChoice& choice) {
  auto& cs = choice.candidates;
  const auto from_nominal = [&](std::size_t i) {
    return rotation_apart_deg(cs[i].T_cad_scan, Transform::Identity());
  };
  std::size_t nominal = choice.best;
  for (std::size_t i = 0; i < cs.size(); ++i)
    if (cs[i].equivalent && from_nominal(i) < from_nominal(nominal)) nominal = i;
  if (nominal == choice.best) return;
  cs[choice.best].equivalent = true;  // the same answer as the one taken
  cs[nominal].equivalent = false;
  choice.best = nominal;
}

}  // namespace

double model_sample_spacing(const KdTree& model_tree) {
  if (model_tree.size() < 2) return 0.0;
  return median_neighbour_spacing(model_tree, strided_sample(model_tree.points(), kSpacingSamples));
}

namespace {

// The model sample that explains q best among its nearest ones: least tangent-plane distance
// plus distance beyond `spacing_mm`. Near an edge the nearest sample may lie on the neighbouring
// face (or on the sheet's other side), whose plane is not the point's. With the point's normal
// `facing` (non-zero: a one-sided scan of a solid), only samples facing the same way count
// (analysis/registration/facing.hpp). Returns that error, mm^2, capped at cap2 (then `best` is
// the nearest sample).
double best_sample(const KdTree& tree, const std::vector<Vec3>& normals, double spacing_mm,
                   double cap2, const Vec3& q, const Vec3& facing, std::uint32_t& best) {
  std::array<std::uint32_t, kScoreNeighbors> index{};
  std::array<double, kScoreNeighbors> d2{};
  std::size_t found = facing.isZero() ? 0
                                      : tree.knn_along(q, normals, facing, kScoreNeighbors,
                                                       index.data(), d2.data());
  // Without the rule, or where no sample at all faces the point's way: the nearest ones.
  if (found == 0) found = tree.knn(q, kScoreNeighbors, index.data(), d2.data());
  const bool planes = normals.size() == tree.size();
  double e2 = cap2;
  best = index[0];
  for (std::size_t k = 0; k < found; ++k) {
    const Vec3 d = q - tree.points()[index[k]];
    const double beyond = std::max(0.0, std::sqrt(d2[k]) - spacing_mm);
    const double across = planes ? normals[index[k]].dot(d) : std::sqrt(d2[k]);
    const double e = across * across + beyond * beyond;
    if (e < e2) e2 = e, best = index[k];
  }
  return e2;
}

// The normal of source point i turned by T, or zero without normals (no facing rule).
Vec3 turned_normal(const std::vector<Vec3>& source_normals, std::size_t i, const Transform& T) {
  return source_normals.empty() ? Vec3::Zero() : Vec3(T.linear() * source_normals[i]);
}

// ICP pairs by the same rule as the score. `source_normals`: one per source point, or empty.
IcpPairSearch best_sample_pairs(const KdTree& tree, const std::vector<Vec3>& normals,
                                const std::vector<Vec3>& source_normals, double spacing_mm) {
  const bool planes = normals.size() == tree.size();
  return [&tree, &normals, &source_normals, spacing_mm, planes](
             const std::vector<Vec3>& source, const Transform& T, std::size_t begin,
             std::size_t end, std::vector<IcpPair>& pairs) {
    const double inf = std::numeric_limits<double>::infinity();
    for (std::size_t i = begin; i < end; ++i) {
      const Vec3 q = T * source[i];
      std::uint32_t best = 0;
      best_sample(tree, normals, spacing_mm, inf, q, turned_normal(source_normals, i, T), best);
      IcpPair& p = pairs[i];
      p.valid = true;
      p.point = tree.points()[best];
      if (planes) p.normal = normals[best];
      p.squared_distance_mm2 = (q - p.point).squaredNorm();
    }
  };
}

double surface_score(const FacingSample& sample, const Transform& T, const KdTree& model_tree,
                     const std::vector<Vec3>& model_normals, double spacing_mm, double cap_mm) {
  if (sample.points.empty() || model_tree.empty()) return 0.0;
  const double cap2 = cap_mm * cap_mm;
  double sum = 0.0;  // serial: a few thousand points, in a fixed order
  std::uint32_t best = 0;
  for (std::size_t i = 0; i < sample.points.size(); ++i)
    sum += best_sample(model_tree, model_normals, spacing_mm, cap2, T * sample.points[i],
                       turned_normal(sample.normals, i, T), best);
  return sum / static_cast<double>(sample.points.size());
}

}  // namespace

double exact_surface_score(const std::vector<Vec3>& points, const std::vector<Vec3>& normals,
                           const Transform& T, const SurfaceDistance& exact, double cap_mm) {
  if (points.empty()) return 0.0;
  const double cap2 = cap_mm * cap_mm;
  const bool facing = normals.size() == points.size();
  double sum = 0.0;  // serial, in a fixed order
  for (std::size_t i = 0; i < points.size(); ++i) {
    const SurfaceHit hit = exact.closest(T * points[i]);
    const double d2 = hit.signed_distance_mm * hit.signed_distance_mm;
    // A foot on a rim between the skins has its normal across the point's: only a clearly
    // opposed one is the other skin.
    const bool other_skin = facing && hit.normal.dot(T.linear() * normals[i]) < -0.5;
    sum += other_skin || !(d2 < cap2) ? cap2 : d2;
  }
  return sum / static_cast<double>(points.size());
}

double robust_surface_score(const std::vector<Vec3>& points, const Transform& T,
                            const KdTree& model_tree, const std::vector<Vec3>& model_normals,
                            double spacing_mm, double cap_mm) {
  return surface_score({points, {}}, T, model_tree, model_normals, spacing_mm, cap_mm);
}

// Some 65 lines: refine every finalist, score it, then rank and test the runner-up for equivalence;
// the three steps share the same points and scores, kept together so the comparison reads as fair.
Expected<OrientationChoice> choose_orientation(
    const std::vector<Vec3>& scan, const KdTree& model_tree, const std::vector<Vec3>& model_normals,
    const std::vector<Transform>& starts, const OrientationSettings& settings,
    const IcpSettings& icp_settings, int threads, const std::vector<Vec3>& scan_normals) {
  if (starts.empty()) return fail("orientation: no candidate pose");
  if (scan.empty() || model_tree.empty()) return fail("orientation: empty scan or model");
  const bool facing = !scan_normals.empty();
  if (facing && (scan_normals.size() != scan.size() || model_normals.size() != model_tree.size()))
    return fail("orientation: the facing rule needs one normal per scan and per model point");
  const FacingSample refine_sample = facing_sample(scan, scan_normals, settings.refine_points);
  const FacingSample score_sample = facing_sample(scan, scan_normals, settings.score_points);
  const double spacing = settings.spacing_allowance * model_sample_spacing(model_tree);
  const IcpPairSearch pairs =
      best_sample_pairs(model_tree, model_normals, refine_sample.normals, spacing);
  IcpSettings s = icp_settings;
  s.max_iterations = settings.refine_iterations;
  s.threads = 1;  // parallel over the candidates instead
  OrientationChoice choice;
  choice.candidates.resize(starts.size());
  parallel_tasks(starts.size(), threads, [&](std::size_t i) {
    OrientationCandidate& c = choice.candidates[i];
    c.T_cad_scan = starts[i];
    auto fit = icp(refine_sample.points, pairs, starts[i], s);
    if (fit) c.T_cad_scan = fit->T_target_source;
    c.score_mm2 = surface_score(score_sample, c.T_cad_scan, model_tree, model_normals, spacing,
                                settings.score_cap_mm);
  });
  const auto& cs = choice.candidates;
  for (std::size_t i = 1; i < cs.size(); ++i)
    if (cs[i].score_mm2 < cs[choice.best].score_mm2) choice.best = i;
  const OrientationCandidate& best = cs[choice.best];
  // The next distinct orientation that is not the same answer on a symmetric model.
  // A symmetry maps outward normals onto outward normals: the model's own follow the same rule.
  const FacingSample model_sample = facing_sample(
      model_tree.points(), facing ? model_normals : std::vector<Vec3>{}, kEquivalenceSamples);
  const IcpPairSearch self_pairs =
      best_sample_pairs(model_tree, model_normals, model_sample.normals, spacing);
  // To convergence: an exact symmetry leaves no error. A symmetry of the model maps its centroid
  // onto itself, which also fixes the directions the surface leaves free (a profile's length).
  IcpSettings self_settings = s;
  self_settings.error_ratio_stop = 0.0;
  Vec3 centroid = Vec3::Zero();
  for (const Vec3& p : model_tree.points()) centroid += p;
  centroid /= static_cast<double>(model_tree.size());
  self_settings.max_iterations = kEquivalenceIterations;
  double second = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < cs.size(); ++i) {
    if (i == choice.best ||
        rotation_apart_deg(cs[i].T_cad_scan, best.T_cad_scan) <= settings.distinct_pose_deg)
      continue;
    // Only a candidate that fits near the best is tested for equivalence (the others can be
    // neither ambiguous nor settled): the model moved by the motion between the two, refined onto
    // itself (the two fits carry noise and springback, so their motion is near the model's
    // symmetry, not on it).
    const bool near_best =
        best.score_mm2 >=
        std::min(settings.settle_ratio, settings.ambiguous_error_ratio) * cs[i].score_mm2;
    if (near_best) {
      Transform T_cad_cad = cs[i].T_cad_scan * best.T_cad_scan.inverse();
      T_cad_cad.translation() += centroid - T_cad_cad * centroid;
      auto self_fit = icp(model_sample.points, self_pairs, T_cad_cad, self_settings);
      if (self_fit) T_cad_cad = self_fit->T_target_source;
      const double self = surface_score(model_sample, T_cad_cad, model_tree, model_normals, spacing,
                                        settings.score_cap_mm);
      if (std::sqrt(self) <= settings.equivalent_rms_mm) {
        choice.candidates[i].equivalent = true;
        choice.symmetric_model = true;
        continue;
      }
    }
    second = std::min(second, cs[i].score_mm2);
  }
  if (choice.symmetric_model) take_nearest_nominal(choice);
  const double best_score = cs[choice.best].score_mm2;
  choice.ambiguity = std::isfinite(second) && second > 0.0 ? best_score / second : 0.0;
  if (std::isfinite(second) && second <= 0.0) choice.ambiguity = 1.0;
  choice.ambiguous = choice.ambiguity > settings.ambiguous_error_ratio;
  return choice;
}

}  // namespace springscan::analysis
