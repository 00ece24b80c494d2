#include "analysis/springback/local_fit.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <unordered_map>

#include "analysis/core/parallel.hpp"
#include "analysis/registration/facing.hpp"

namespace springscan::analysis {
namespace {

// The fewest pairs a local fit solves with: three planes fix the determined directions of a
// flange (its offset and tilt); the engine holds the rest.
constexpr int kMinLocalPairs = 3;

// Pairs with the exact foot on the CAD surface (PartModel::distance) within the limit
// (0 = no limit, as for IcpSettings).
IcpPairSearch exact_surface_pairs(const PartModel& model, double max_distance_mm) {
  const double limit =
      max_distance_mm > 0.0 ? max_distance_mm : std::numeric_limits<double>::infinity();
  return [&model, limit](const std::vector<Vec3>& source, const Transform& T, std::size_t begin,
                         std::size_t end, std::vector<IcpPair>& pairs) {
    for (std::size_t i = begin; i < end; ++i) {
      const Vec3 p = T * source[i];
      const SurfaceHit hit = model.distance->closest(p);
      const double d2 = (p - hit.foot).squaredNorm();
      pairs[i] = {hit.foot, hit.normal, d2, std::sqrt(d2) <= limit};
    }
  };
}

// The points of `source` by cell of the plane normal to `axis`, cells `cell_mm` square.
std::unordered_map<std::int64_t, std::vector<std::uint32_t>> cells_across(
    const std::vector<Vec3>& source, const Vec3& axis, double cell_mm) {
  const Vec3 u = axis.unitOrthogonal(), v = axis.cross(u);
  std::unordered_map<std::int64_t, std::vector<std::uint32_t>> cells;
  for (std::size_t i = 0; i < source.size(); ++i) {
    const auto a = static_cast<std::int64_t>(std::floor(u.dot(source[i]) / cell_mm));
    const auto b = static_cast<std::int64_t>(std::floor(v.dot(source[i]) / cell_mm));
    cells[(a << 32) ^ (b & 0xffffffff)].push_back(static_cast<std::uint32_t>(i));
  }
  return cells;
}

// Both skins of a standing flange seen (two passes from both sides, no scan normals): per cell
// of the flange's plane, its points' heights along the flange normal fall in two layers one
// sheet thickness apart, the material between them. Marks the points of the upper layer +1 (the
// skin facing +axis) and of the lower -1; 0 where a cell shows one layer (the caller's vote
// decides there). Two layers: the largest gap between sorted heights at least half the
// thickness, the layers' medians 0.6-1.4 thicknesses apart, each layer at least kMinLayerPoints
// and a tenth of the cell (stray points and outliers make no layer). Cells of 4 mm, or 8 and 16
// mm until half the points lie in cells of kMinCellPoints (the local fits get thinned points:
// the front panel's walls had 6 a 4 mm cell).
std::vector<int> skin_layers(const std::vector<Vec3>& source, const Vec3& axis, double thickness) {
  constexpr std::size_t kMinLayerPoints = 5;
  constexpr std::size_t kMinCellPoints = 20;
  std::vector<int> side(source.size(), 0);
  if (!(thickness > 0.0)) return side;
  std::unordered_map<std::int64_t, std::vector<std::uint32_t>> cells;
  for (const double cell_mm : {4.0, 8.0, 16.0}) {
    cells = cells_across(source, axis, cell_mm);
    std::size_t in_full_cells = 0;
    for (const auto& [key, members] : cells)
      if (members.size() >= kMinCellPoints) in_full_cells += members.size();
    if (2 * in_full_cells >= source.size()) break;
  }
  std::vector<std::pair<double, std::uint32_t>> h;
  for (auto& [key, members] : cells) {
    if (members.size() < 2 * kMinLayerPoints) continue;
    h.clear();
    for (const std::uint32_t i : members) h.emplace_back(axis.dot(source[i]), i);
    std::sort(h.begin(), h.end());
    std::size_t split = 0;
    double gap = 0.0;
    for (std::size_t k = 1; k < h.size(); ++k)
      if (h[k].first - h[k - 1].first > gap) gap = h[k].first - h[k - 1].first, split = k;
    const std::size_t lower = split, upper = h.size() - split;
    const std::size_t least = std::max(kMinLayerPoints, h.size() / 10);
    if (gap < 0.5 * thickness || lower < least || upper < least) continue;
    const double apart = h[split + upper / 2].first - h[lower / 2].first;
    if (apart < 0.6 * thickness || apart > 1.4 * thickness) continue;
    for (std::size_t k = 0; k < h.size(); ++k) side[h[k].second] = k < split ? -1 : 1;
  }
  return side;
}

// A flange's points pair only with samples whose normal is within 60 deg of the skin they see:
// its own skin (and the bend zone beside it), never the sheet's edge faces and hole walls, whose
// normals lie in the flange's plane. Without scan normals every point of a flange takes the
// flange's normal (seen_side_normals), and the side panel's 15 mm tab, 81 points, took 12 of
// them from its edges and a hole's rim, paired with those faces' samples (a dot product of
// rounding size, positive): its bend came out 0.05 deg off.
constexpr double kLocalFacingMinDot = 0.5;

// On a solid sheet both skins of a flange lie within a sheet thickness of its scan points, and
// a nearest-sample pair may cross the sheet: the fit then settles between the skins (its rms
// near half the thickness). The skin the scan sees is the one most points' nearest samples lie
// on (only the sample spacing separates a point from it, the thickness adds to the other's);
// every point then pairs only with samples facing that way (registration/facing.hpp). Where a
// cell of the flange shows both skins as two layers (skin_layers: a standing flange seen from
// both sides by two passes, without scan normals), each layer takes its own skin: the vote
// gave all of them one, and the front panel's and cover flange's walls fitted between their
// skins at rms 1 mm. A scan that brings its normals (toward the scanner) says it per point
// instead. A surface model has one skin: nearest pairs.
std::vector<Vec3> seen_side_normals(const KdTree& tree, const std::vector<Vec3>& normals,
                                    const std::vector<Vec3>& source, double thickness) {
  // The flange's normal direction, sign aside: the principal axis of the nearest samples'
  // normals (edge and hole faces among them weigh little).
  std::vector<std::uint32_t> nearest(source.size());
  Mat3 scatter = Mat3::Zero();
  for (std::size_t i = 0; i < source.size(); ++i) {
    nearest[i] = tree.nearest(source[i])->index;
    scatter += normals[nearest[i]] * normals[nearest[i]].transpose();
  }
  const Eigen::SelfAdjointEigenSolver<Mat3> eig(scatter);
  const Vec3 axis = eig.eigenvectors().col(2);
  long votes = 0;
  for (std::uint32_t j : nearest) {
    const double c = normals[j].dot(axis);
    if (std::abs(c) > 0.5) votes += c > 0.0 ? 1 : -1;
  }
  const Vec3 voted = votes >= 0 ? axis : Vec3(-axis);
  std::vector<Vec3> out(source.size(), voted);
  const std::vector<int> layer = skin_layers(source, axis, thickness);
  for (std::size_t i = 0; i < source.size(); ++i)
    if (layer[i] != 0) out[i] = layer[i] > 0 ? axis : Vec3(-axis);
  return out;
}

std::optional<Error> check_inputs(const LocalFitTarget& target, const PointCloud& scan,
                                  const std::vector<std::uint32_t>& indices,
                                  const LocalFitSettings& st) {
  const PartModel& model = target.model();
  if (auto error = validate(st)) return error;
  if (indices.size() < static_cast<std::size_t>(st.min_points))
    return fail("local_fit: subset has " + std::to_string(indices.size()) +
                " points, fewer than min_points " + std::to_string(st.min_points));
  if (model.samples.empty() || model.samples.normals.size() != model.samples.size())
    return fail("local_fit: the model samples have no normals");
  if (st.correspondence == LocalFitCorrespondence::kExactSurface && !model.distance)
    return fail("local_fit: kExactSurface needs PartModel::distance");
  for (std::uint32_t i : indices) {
    if (i >= scan.size())
      return fail("local_fit: index " + std::to_string(i) + " outside the scan of " +
                  std::to_string(scan.size()) + " points");
    if (!scan.points[i].allFinite())
      return fail("local_fit: point " + std::to_string(i) + " is not finite");
  }
  return std::nullopt;
}

}  // namespace

LocalFitTarget::LocalFitTarget(const PartModel& model)
    : model_(&model),
      tree_(model.samples.points),
      two_skins_(std::any_of(model.segmentation.flanges.begin(), model.segmentation.flanges.end(),
                             [](const Flange& f) { return f.thickness_mm > 0.0; })) {
  for (const Flange& f : model.segmentation.flanges)
    if (f.thickness_mm > 0.0 &&
        (sheet_thickness_mm_ == 0.0 || f.thickness_mm < sheet_thickness_mm_))
      sheet_thickness_mm_ = f.thickness_mm;
}

IcpSettings icp_settings(const LocalFitSettings& st) {
  IcpSettings s;
  s.method = IcpMethod::kPointToPlane;
  s.max_iterations = st.max_iterations;
  s.max_inner_iterations = st.max_inner_iterations;
  s.max_correspondence_distance_mm = st.max_correspondence_distance_mm;
  s.trimmed_fraction = 0.0;
  s.inlier_sigma_factor = st.inlier_sigma_factor;
  s.min_inlier_threshold_mm = st.min_inlier_threshold_mm;
  s.kernel = RobustKernel::kNone;
  s.degenerate_eigenvalue_ratio = st.degenerate_eigenvalue_ratio;
  s.min_pairs = kMinLocalPairs;
  s.min_error_mm = 0.0;
  s.error_ratio_stop = 0.0;
  s.convergence_rotation_deg = st.convergence_rotation_deg;
  s.convergence_translation_mm = st.convergence_translation_mm;
  s.threads = st.threads;
  return s;
}

std::optional<Error> validate(const LocalFitSettings& st, std::string_view context) {
  if (st.min_points < kMinLocalPairs || st.min_points > 1'000'000'000)
    return fail(std::string(context) + "min_points = " + std::to_string(st.min_points) +
                ": must be in [3, 1e9]");
  return validate(icp_settings(st), context);
}

Expected<LocalFitResult> local_fit(const LocalFitTarget& target, const PointCloud& scan,
                                   const std::vector<std::uint32_t>& indices,
                                   const LocalFitSettings& st) {
  if (auto error = check_inputs(target, scan, indices, st)) return *error;
  std::vector<Vec3> source;
  source.reserve(indices.size());
  for (std::uint32_t i : indices) source.push_back(scan.points[i]);
  const PartModel& model = target.model();
  // ICP: find the pairs, then solve the point-to-plane problem on them to convergence (a few
  // Gauss-Newton steps); stop when fresh pairs no longer move the subset.
  const bool exact = st.correspondence == LocalFitCorrespondence::kExactSurface;
  const bool facing = !exact && target.two_skins();
  std::vector<Vec3> seen;
  if (facing && scan.normals.size() == scan.size()) {
    for (std::uint32_t i : indices) seen.push_back(scan.normals[i]);
  } else if (facing) {
    seen = seen_side_normals(target.tree(), model.samples.normals, source,
                             target.sheet_thickness_mm());
  }
  const IcpPairSearch search =
      exact    ? exact_surface_pairs(model, st.max_correspondence_distance_mm)
      : facing ? nearest_facing_pairs(target.tree(), model.samples.normals, seen,
                                      st.max_correspondence_distance_mm, kLocalFacingMinDot)
               : nearest_point_pairs(target.tree(), model.samples.normals,
                                     st.max_correspondence_distance_mm);
  auto fit = icp(source, search, Transform::Identity(), icp_settings(st));
  if (!fit) return fit.error().prepend("local_fit: ");
  if (fit->stop == IcpStop::kTooFewPairs)
    return fail("local_fit: fewer than " + std::to_string(kMinLocalPairs) + " of " +
                std::to_string(source.size()) + " points within " +
                std::to_string(st.max_correspondence_distance_mm) + " mm of the model");
  LocalFitResult result;
  result.T_model_subset = fit->T_target_source;
  result.rms_mm = fit->rms_mm();
  result.points = source.size();
  result.inliers = fit->inliers;
  result.iterations = fit->iterations;
  result.converged = fit->converged;
  result.error_history = std::move(fit->error_history);
  result.determined_directions = fit->determined_directions;
  return result;
}

std::vector<std::uint32_t> points_in_box(const PointCloud& scan, const Eigen::AlignedBox3d& box) {
  std::vector<std::uint32_t> out;
  for (std::size_t i = 0; i < scan.size(); ++i)
    if (box.contains(scan.points[i])) out.push_back(static_cast<std::uint32_t>(i));
  return out;
}

std::vector<std::uint32_t> points_on_faces(const LocalFitTarget& target, const PointCloud& scan,
                                           const std::vector<int>& face_ids, double max_distance_mm,
                                           int threads) {
  const auto& samples = target.model().samples;
  std::vector<std::uint8_t> keep(scan.size(), 0);
  if (samples.face_ids.size() == samples.size()) {
    parallel_blocks(scan.size(), threads, [&](std::size_t, std::size_t lo, std::size_t hi) {
      for (std::size_t i = lo; i < hi; ++i) {
        const auto nn = target.tree().nearest(scan.points[i], max_distance_mm);
        keep[i] = nn && std::find(face_ids.begin(), face_ids.end(), samples.face_ids[nn->index]) !=
                            face_ids.end();
      }
    });
  }
  std::vector<std::uint32_t> out;
  for (std::size_t i = 0; i < keep.size(); ++i)
    if (keep[i]) out.push_back(static_cast<std::uint32_t>(i));
  return out;
}

}  // namespace springscan::analysis
