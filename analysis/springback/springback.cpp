#include "analysis/springback/springback.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <iterator>
#include <limits>
#include <numbers>
#include <unordered_map>

#include "analysis/core/kdtree.hpp"
#include "analysis/core/parallel.hpp"
#include "analysis/springback/bend_shape.hpp"

namespace springscan::analysis {
namespace {

constexpr double kRadToDeg = 180.0 / std::numbers::pi;
constexpr std::size_t kBlock = 4096;
constexpr std::int32_t kNoFlange = -1;
// A flange fit with this many scan points or more shares the threads (fit_flanges).
constexpr std::size_t kSharedFitPoints = 20000;

std::string check(const PartModel& model, const SpringbackSettings& st) {
  const PointCloud& s = model.samples;
  if (s.empty() || s.normals.size() != s.size() || s.face_ids.size() != s.size())
    return "model samples need normals and face ids (" + std::to_string(s.size()) + " samples)";
  if (!(st.bend_margin_mm >= 0.0 && st.bend_margin_mm < 1000.0))
    return "bend_margin_mm " + std::to_string(st.bend_margin_mm) + " outside [0, 1000)";
  if (!(st.bend_margin_fraction >= 0.0 && st.bend_margin_fraction <= 1.0))
    return "bend_margin_fraction " + std::to_string(st.bend_margin_fraction) + " outside [0, 1]";
  if (!(st.min_bend_margin_mm >= 0.0 && st.min_bend_margin_mm < 1000.0))
    return "min_bend_margin_mm " + std::to_string(st.min_bend_margin_mm) + " outside [0, 1000)";
  if (!(st.max_angle_sigma_deg >= 0.0))
    return "max_angle_sigma_deg " + std::to_string(st.max_angle_sigma_deg) + " must be >= 0";
  if (st.dense_flange_points < 0)
    return "dense_flange_points " + std::to_string(st.dense_flange_points) + " must be >= 0";
  if (!(st.assignment_distance_mm > 0.0))
    return "assignment_distance_mm " + std::to_string(st.assignment_distance_mm) + " must be > 0";
  if (!(st.shape.station_spacing_mm > 0.0 && st.shape.station_spacing_mm <= 10000.0))
    return "shape.station_spacing_mm " + std::to_string(st.shape.station_spacing_mm) +
           " outside (0, 10000]";
  if (st.shape.min_stations < 1 || st.shape.min_stations > 1000)
    return "shape.min_stations " + std::to_string(st.shape.min_stations) + " outside [1, 1000]";
  if (!(st.max_fit_rms_ratio >= 0.0))
    return "max_fit_rms_ratio " + std::to_string(st.max_fit_rms_ratio) + " must be >= 0";
  if (!(st.hem_angle_deg > 0.0 && st.hem_angle_deg <= 180.0))
    return "hem_angle_deg " + std::to_string(st.hem_angle_deg) + " outside (0, 180]";
  if (st.max_scan_points < 0)
    return "max_scan_points " + std::to_string(st.max_scan_points) + " must be >= 0";
  const auto& flanges = model.segmentation.flanges;
  const auto known = [&flanges](int id) {
    return std::any_of(flanges.begin(), flanges.end(),
                       [id](const Flange& f) { return f.id == id; });
  };
  for (const Bend& b : model.segmentation.bends)
    if (!known(b.flange_a) || !known(b.flange_b))
      return "bend " + std::to_string(b.id) + " joins unknown flange " +
             std::to_string(known(b.flange_a) ? b.flange_b : b.flange_a);
  return {};
}

// The bend margin of each flange (segmentation order): bend_margin_mm on a deep flange, a
// fraction of the depth on a short tab (its depth: how far its farthest sample lies from the
// nearest of its bends' axes), never below min_bend_margin_mm. A fixed 2 mm margin leaves a
// 6 mm tab of a 0.8 mm sheet (Ri 1.2) under 3 mm of flat; the floor still keeps points that a
// small misalignment puts on the far side of the tangent line off the flange.
std::vector<double> flange_margins(const PartModel& model, const SpringbackSettings& st) {
  const auto& seg = model.segmentation;
  const PointCloud& s = model.samples;
  std::unordered_map<int, std::size_t> flange_of_face;
  for (std::size_t f = 0; f < seg.flanges.size(); ++f)
    for (int face : seg.flanges[f].face_ids) flange_of_face[face] = f;
  std::vector<std::vector<const Bend*>> bends(seg.flanges.size());
  for (const Bend& b : seg.bends)
    for (std::size_t f = 0; f < seg.flanges.size(); ++f)
      if (seg.flanges[f].id == b.flange_a || seg.flanges[f].id == b.flange_b)
        bends[f].push_back(&b);
  std::vector<double> depth(seg.flanges.size(), 0.0);
  for (std::size_t i = 0; i < s.size(); ++i) {
    const auto it = flange_of_face.find(s.face_ids[i]);
    if (it == flange_of_face.end() || bends[it->second].empty()) continue;
    double nearest = std::numeric_limits<double>::infinity();
    for (const Bend* b : bends[it->second]) {
      const Vec3 d = s.points[i] - b->axis_point, a = b->axis_direction.normalized();
      nearest = std::min(nearest, (d - d.dot(a) * a).norm());
    }
    depth[it->second] = std::max(depth[it->second], nearest);
  }
  std::vector<double> margin(seg.flanges.size(), st.bend_margin_mm);
  for (std::size_t f = 0; f < margin.size(); ++f)
    margin[f] = std::min(st.bend_margin_mm,
                         std::max(st.min_bend_margin_mm, st.bend_margin_fraction * depth[f]));
  return margin;
}

// Per model sample: the index (into segmentation.flanges) of its flange, or kNoFlange for bend
// and other faces and for flange samples within their flange's margin of a bend sample. The
// margin is measured on the model, so it does not depend on how far the part sprang back.
std::vector<std::int32_t> sample_labels(const PartModel& model, const std::vector<double>& margin,
                                        int threads) {
  std::unordered_map<int, std::int32_t> flange_of_face;
  const auto& flanges = model.segmentation.flanges;
  for (std::size_t f = 0; f < flanges.size(); ++f)
    for (int face : flanges[f].face_ids) flange_of_face[face] = static_cast<std::int32_t>(f);
  const PointCloud& s = model.samples;
  std::vector<std::int32_t> labels(s.size(), kNoFlange);
  std::vector<Vec3> bend_points;
  for (std::size_t i = 0; i < s.size(); ++i) {
    const auto it = flange_of_face.find(s.face_ids[i]);
    if (it != flange_of_face.end())
      labels[i] = it->second;
    else
      bend_points.push_back(s.points[i]);  // bend and other faces: never fitted as flange
  }
  if (bend_points.empty()) return labels;
  const KdTree bends(std::move(bend_points));
  for_each_block(s.size(), kBlock, threads, [&](std::size_t, std::size_t lo, std::size_t hi) {
    for (std::size_t i = lo; i < hi; ++i) {
      if (labels[i] == kNoFlange) continue;
      const double m = margin[static_cast<std::size_t>(labels[i])];
      if (m > 0.0 && bends.nearest(s.points[i], m)) labels[i] = kNoFlange;
    }
  });
  return labels;
}

// Interleaves the bits of three 21-bit cell coordinates (a Morton / Z-order key).
std::uint64_t morton_key(const Vec3& p, const Vec3& origin) {
  constexpr double kCellMm = 2.0;
  std::uint64_t key = 0;
  for (int axis = 0; axis < 3; ++axis) {
    const double cell = std::clamp((p[axis] - origin[axis]) / kCellMm, 0.0, 2097151.0);
    const auto c = static_cast<std::uint64_t>(cell);
    for (int bit = 0; bit < 21; ++bit) key |= ((c >> bit) & 1u) << (3 * bit + axis);
  }
  return key;
}

// Every `stride`-th scan point, in Z-order: neighbouring queries then walk the same part of
// the k-d tree, which halves their cost on a randomly ordered scan.
std::vector<std::uint32_t> thinned_in_space_order(const PointCloud& scan, std::size_t stride) {
  // Non-finite points (NaN, inf) are left out here: they belong to no flange.
  const auto finite = [&scan](std::size_t i) { return scan.points[i].allFinite(); };
  Vec3 origin = Vec3::Constant(std::numeric_limits<double>::infinity());
  for (std::size_t i = 0; i < scan.size(); i += stride)
    if (finite(i)) origin = origin.cwiseMin(scan.points[i]);
  std::vector<std::pair<std::uint64_t, std::uint32_t>> keyed;
  keyed.reserve(scan.size() / stride + 1);
  for (std::size_t i = 0; i < scan.size(); i += stride)
    if (finite(i))
      keyed.emplace_back(morton_key(scan.points[i], origin), static_cast<std::uint32_t>(i));
  std::sort(keyed.begin(), keyed.end());
  std::vector<std::uint32_t> order;
  order.reserve(keyed.size());
  for (const auto& k : keyed) order.push_back(k.second);
  return order;
}

// cos(assignment_normal_deg): the assignment's floor on the dot product of unit normals.
double assignment_min_dot(const SpringbackSettings& st) {
  return std::cos(st.assignment_normal_deg * std::numbers::pi / 180.0);
}

// The nearest model sample to scan point i. With scan normals, the nearest whose normal agrees
// with the point's within assignment_normal_deg: springback carries a flange's points over its
// neighbour's samples (the side panel's bottom lip, turned 6 deg by three bends and seen from
// below, lay nearer the end wall's samples than its own and tilted that wall 0.15 deg), and
// their normals tell them apart. A solid's samples face out of the material and the scan's
// normals toward the scanner, so the skin seen agrees in sign; a surface model's faces are
// oriented either way. `min_dot`: assignment_min_dot(st), computed once by the caller.
std::optional<Neighbor> assignment_sample(const LocalFitTarget& target, const PointCloud& scan,
                                          std::uint32_t i, const SpringbackSettings& st,
                                          double min_dot) {
  const Vec3& p = scan.points[i];
  const std::vector<Vec3>& normals = target.model().samples.normals;
  if (!scan.has_normals() || normals.size() != target.tree().size())
    return target.tree().nearest(p, st.assignment_distance_mm);
  const Vec3& n = scan.normals[i];
  auto best = target.tree().nearest_along(p, normals, n, st.assignment_distance_mm, 0, min_dot);
  if (target.two_skins()) return best;
  const auto other =
      target.tree().nearest_along(p, normals, -n, st.assignment_distance_mm, 0, min_dot);
  if (other && (!best || other->squared_distance < best->squared_distance)) best = other;
  return best;
}

// The points of `order` per label (flanges, then bend zones), by the label of their assignment
// sample.
std::vector<std::vector<std::uint32_t>> assign_points(
    const LocalFitTarget& target, const std::vector<std::int32_t>& labels, std::size_t label_count,
    const PointCloud& scan, const std::vector<std::uint32_t>& order, const SpringbackSettings& st) {
  std::vector<std::int32_t> flange_of(order.size(), kNoFlange);
  const double min_dot = assignment_min_dot(st);
  for_each_block(order.size(), kBlock, st.threads,
                 [&](std::size_t, std::size_t lo, std::size_t hi) {
                   for (std::size_t k = lo; k < hi; ++k) {
                     const auto nn = assignment_sample(target, scan, order[k], st, min_dot);
                     if (nn) flange_of[k] = labels[nn->index];
                   }
                 });
  std::vector<std::vector<std::uint32_t>> out(label_count);
  for (std::size_t k = 0; k < order.size(); ++k)
    if (flange_of[k] != kNoFlange) out[static_cast<std::size_t>(flange_of[k])].push_back(order[k]);
  return out;
}

// A flange short of points after thinning takes more from the full scan, so that a short tab
// is fitted at the scan's own density (thinning is for the large flanges, whose planes are
// fixed long before): every `every`-th scan point inside the flange's box (its labelled
// samples' principal axes, widened by kDenseBoxMm), labelled like the thinned points, chosen so
// about dense_flange_points more come. Few queries: only the small flanges' boxes.
void add_dense_points(const LocalFitTarget& target, const std::vector<std::int32_t>& labels,
                      const PointCloud& scan, std::size_t stride, const SpringbackSettings& st,
                      std::vector<std::vector<std::uint32_t>>& assigned, std::size_t flanges) {
  constexpr double kDenseBoxMm = 2.0;
  if (stride <= 1 || st.dense_flange_points <= 0) return;
  const auto wanted = static_cast<std::size_t>(st.dense_flange_points);
  struct Box {
    std::int32_t flange = kNoFlange;
    std::size_t every = 1;
    Vec3 centre = Vec3::Zero();
    Mat3 axes = Mat3::Identity();  // rows: principal directions
    Vec3 half = Vec3::Zero();
  };
  // Principal axes of each flange's labelled samples.
  const PointCloud& s = target.model().samples;
  std::vector<Vec3> sum(flanges, Vec3::Zero());
  std::vector<Mat3> second(flanges, Mat3::Zero());
  std::vector<std::size_t> count(flanges, 0);
  for (std::size_t i = 0; i < s.size(); ++i) {
    if (labels[i] < 0 || static_cast<std::size_t>(labels[i]) >= flanges) continue;
    const auto f = static_cast<std::size_t>(labels[i]);
    sum[f] += s.points[i];
    second[f] += s.points[i] * s.points[i].transpose();
    ++count[f];
  }
  std::vector<Box> boxes;
  std::vector<char> small(flanges, 0);
  for (std::size_t f = 0; f < flanges; ++f) {
    // A flange the thinned scan does not see at all gains nothing from the full one.
    if (assigned[f].empty() || assigned[f].size() >= wanted || count[f] < 3) continue;
    Box b;
    b.flange = static_cast<std::int32_t>(f);
    b.every = std::max<std::size_t>(1, assigned[f].size() * stride / wanted);
    b.centre = sum[f] / static_cast<double>(count[f]);
    const Mat3 cov = second[f] / static_cast<double>(count[f]) - b.centre * b.centre.transpose();
    b.axes = Eigen::SelfAdjointEigenSolver<Mat3>(cov).eigenvectors().transpose();
    boxes.push_back(b);
    small[f] = 1;
  }
  if (boxes.empty()) return;
  for (std::size_t i = 0; i < s.size(); ++i) {
    if (labels[i] < 0 || static_cast<std::size_t>(labels[i]) >= flanges || !small[labels[i]])
      continue;
    for (Box& b : boxes)
      if (b.flange == labels[i])
        b.half = b.half.cwiseMax((b.axes * (s.points[i] - b.centre)).cwiseAbs());
  }
  for (Box& b : boxes) b.half.array() += kDenseBoxMm;
  const std::size_t n = scan.size();
  const double min_dot = assignment_min_dot(st);
  std::vector<std::vector<std::pair<std::int32_t, std::uint32_t>>> found(block_count(n));
  parallel_blocks(n, st.threads, [&](std::size_t block, std::size_t lo, std::size_t hi) {
    for (std::size_t i = lo; i < hi; ++i) {
      if (i % stride == 0 || !scan.points[i].allFinite()) continue;  // thinned: assigned already
      const Vec3& p = scan.points[i];
      const bool inside = std::any_of(boxes.begin(), boxes.end(), [&](const Box& b) {
        return i % b.every == 0 &&
               ((b.axes * (p - b.centre)).cwiseAbs().array() <= b.half.array()).all();
      });
      if (!inside) continue;
      const auto nn = assignment_sample(target, scan, static_cast<std::uint32_t>(i), st, min_dot);
      if (!nn) continue;
      const std::int32_t label = labels[nn->index];
      if (label >= 0 && static_cast<std::size_t>(label) < flanges && small[label])
        found[block].emplace_back(label, static_cast<std::uint32_t>(i));
    }
  });
  for (const auto& block : found)
    for (const auto& [label, i] : block) assigned[static_cast<std::size_t>(label)].push_back(i);
}

FlangeFit fit_flange(const LocalFitTarget& target, const PointCloud& scan, const Flange& flange,
                     std::vector<std::uint32_t> indices, const SpringbackSettings& st) {
  FlangeFit out;
  out.flange_id = flange.id;
  out.face_ids = flange.face_ids;
  out.indices = std::move(indices);
  const auto min_points =
      static_cast<std::size_t>(std::max({st.min_points_per_flange, st.local_fit.min_points, 3}));
  if (out.indices.size() < min_points) {
    out.status = "flange " + std::to_string(flange.id) + ": " + std::to_string(out.indices.size()) +
                 " scan points, fewer than the " + std::to_string(min_points) +
                 " a plane fit needs (the scan sees little or nothing of it)";
    return out;
  }
  for (std::uint32_t i : out.indices) out.centroid += scan.points[i];
  out.centroid /= static_cast<double>(out.indices.size());
  for (std::uint32_t i : out.indices) {
    const Vec3 d = scan.points[i] - out.centroid;
    out.spread += d * d.transpose();
  }
  LocalFitSettings fit_settings = st.local_fit;
  fit_settings.threads = st.threads;
  auto fit = local_fit(target, scan, out.indices, fit_settings);
  if (!fit) {
    out.status = "flange " + std::to_string(flange.id) + ": " + fit.message();
    return out;
  }
  out.fit = std::move(fit).value();
  out.fitted = true;
  // The data's plane normal: the fit maps data onto the model, so its inverse maps the model
  // normal back. A turn about the normal (left undetermined by the fit) does not change it.
  out.measured_normal = out.fit.T_model_subset.linear().transpose() * flange.normal;
  return out;
}

// fit_flange of every flange (assigned[f] moved out for the first seg.flanges.size()). A
// flange's fit of a few thousand points is one block of the ICP's parallel loops (kParallelBlock
// points), so it ran on one thread while the others waited. So large flanges are fitted one
// after another on all threads, the others side by side on one thread each; a fit's result does
// not depend on its thread count.
std::vector<FlangeFit> fit_flanges(const LocalFitTarget& target, const PointCloud& scan,
                                   const std::vector<Flange>& flanges,
                                   std::vector<std::vector<std::uint32_t>>& assigned,
                                   const SpringbackSettings& st) {
  std::vector<FlangeFit> out(flanges.size());
  std::vector<std::size_t> side_by_side;
  for (std::size_t f = 0; f < flanges.size(); ++f) {
    if (assigned[f].size() < kSharedFitPoints) {
      side_by_side.push_back(f);
      continue;
    }
    out[f] = fit_flange(target, scan, flanges[f], std::move(assigned[f]), st);
  }
  SpringbackSettings one_thread = st;
  one_thread.threads = 1;
  parallel_tasks(side_by_side.size(), st.threads, [&](std::size_t k) {
    const std::size_t f = side_by_side[k];
    out[f] = fit_flange(target, scan, flanges[f], std::move(assigned[f]), one_thread);
  });
  return out;
}

// The median rms of the fitted flanges: the scan's noise as the fits see it (0: none fitted).
double median_fit_rms(const SpringbackResult& result) {
  std::vector<double> rms;
  for (const FlangeFit& f : result.flanges)
    if (f.fitted) rms.push_back(f.fit.rms_mm);
  if (rms.empty()) return 0.0;
  std::nth_element(rms.begin(), rms.begin() + static_cast<long>(rms.size() / 2), rms.end());
  return rms[rms.size() / 2];
}

// A curled wall's plane fit stays far above the noise, and rightly. The curl explains it when
// it is a curl: its radius larger than the flange's extent across (a few millimetres is a fold,
// or stray points of other faces), nearly all points within the shape fit's inlier band, and
// that band as narrow as the noise allows a plane fit (`noise_limit_mm`, as a robust sigma).
// The inlier band is 3 robust sigmas of the residuals about the curl itself, so without the
// last rule any point set passes: the front panel's 18 mm walls, seen edge-on, left 1,000 points
// of their rims and skins that a 27 mm "curl" fitted with a robust sigma of a tenth of a mm.
bool curl_explains_fit(const FlangeShape& shape, double outlier_sigmas, double noise_limit_mm) {
  constexpr double kMinInlierShare = 0.9;
  if (!shape.measured || !shape.curled || shape.local.empty()) return false;
  double s_min = shape.local.front().x(), s_max = s_min;
  for (const Vec3& q : shape.local) s_min = std::min(s_min, q.x()), s_max = std::max(s_max, q.x());
  return std::abs(shape.curl_radius_mm) > s_max - s_min &&
         static_cast<double>(shape.inliers) >=
             kMinInlierShare * static_cast<double>(shape.local.size()) &&
         shape.inlier_threshold_mm <= outlier_sigmas * noise_limit_mm;
}

// A fit whose rms stays far above the other flanges' (the scan's noise as the fits see it)
// measures no plane of the scan, nor does one that ran out of iterations above that noise,
// unless the flange's shape explains it (a curled wall bows millimetres from any plane): its
// bends get no angle, and the status keeps its figures. (A fit at its iteration cap within the
// noise is kept: outliers can keep pairs changing by a hair long after the plane is found; the
// report's local_fit.converged says so.) Runs after the shapes, which it reads.
// Returns the Flange::id of every flange it rejected.
std::vector<int> reject_poor_fits(SpringbackResult& result, const SpringbackSettings& st) {
  std::vector<int> rejected;
  const double median = median_fit_rms(result);
  if (!(median > 0.0) || !(st.max_fit_rms_ratio > 0.0)) return rejected;
  constexpr double kUnconvergedRatio = 2.0;  // an unconverged fit must be this near the noise
  for (FlangeFit& f : result.flanges) {
    if (!f.fitted ||
        curl_explains_fit(f.shape, st.shape.flange.outlier_sigmas, st.max_fit_rms_ratio * median))
      continue;
    const std::string figures = "rms " + std::to_string(f.fit.rms_mm) + " mm over " +
                                std::to_string(f.fit.points) + " points, the median flange fit " +
                                std::to_string(median) + " mm";
    if (!f.fit.converged && f.fit.rms_mm > kUnconvergedRatio * median) {
      f.status = "flange " + std::to_string(f.flange_id) + ": local fit not converged after " +
                 std::to_string(f.fit.iterations) + " iterations (" + figures + ")";
    } else if (f.fit.rms_mm > st.max_fit_rms_ratio * median) {
      f.status = "flange " + std::to_string(f.flange_id) + ": local fit " + figures + ": above " +
                 std::to_string(st.max_fit_rms_ratio) + " x the median, not a plane of the scan";
    } else {
      continue;
    }
    f.fitted = false;
    rejected.push_back(f.flange_id);
  }
  return rejected;
}

// How well a flange fit fixes its tilt about `axis` (radians, one standard deviation): the
// slope error of a line fit, noise / sqrt(sum of squared distances across the bend). The noise
// is the fit's rms, at least the part's median (a few points may fit a plane by chance).
double tilt_sigma_rad(const FlangeFit& f, const Flange& flange, const Vec3& axis, double noise) {
  const Vec3 across = flange.normal.cross(axis);
  if (!(across.norm() > 1e-9)) return std::numeric_limits<double>::infinity();
  const Vec3 u = across.normalized();
  const double s = u.dot(f.spread * u);
  return s > 0.0 ? std::max(f.fit.rms_mm, noise) / std::sqrt(s)
                 : std::numeric_limits<double>::infinity();
}

// What a flange gives its bend's angle, for the status.
std::string flange_figures(const FlangeFit& f, const Flange& flange, const Vec3& axis) {
  const Vec3 across = flange.normal.cross(axis);
  const double s =
      across.norm() > 1e-9 ? across.normalized().dot(f.spread * across.normalized()) : 0.0;
  // The width of an evenly covered strip with the same spread.
  const double width =
      std::sqrt(12.0 * s / static_cast<double>(std::max<std::size_t>(f.indices.size(), 1)));
  return "flange " + std::to_string(f.flange_id) + " " + std::to_string(f.indices.size()) +
         " points over " + std::to_string(width) + " mm across, rms " +
         std::to_string(f.fit.rms_mm) + " mm";
}

// A measured bend whose flanges' points fix its angle less well than max_angle_sigma_deg
// gives no angle: a short tab seen by few points, or a strip of a flange along the bend.
void check_angle_sigma(BendMeasurement& m, const Flange& fa, const Flange& fb, const FlangeFit& a,
                       const FlangeFit& b, double noise, const SpringbackSettings& st) {
  if (!m.measured) return;
  const Vec3 axis = m.axis_direction.normalized();
  const double sa = tilt_sigma_rad(a, fa, axis, noise), sb = tilt_sigma_rad(b, fb, axis, noise);
  m.angle_sigma_deg = std::sqrt(sa * sa + sb * sb) * kRadToDeg;
  if (!(st.max_angle_sigma_deg > 0.0) || m.angle_sigma_deg <= st.max_angle_sigma_deg) return;
  m.measured = false;
  m.status = "bend " + std::to_string(m.bend_id) + " not measured: its flanges fix its angle to " +
             std::to_string(m.angle_sigma_deg) + " deg (1 sigma), above max_angle_sigma_deg " +
             std::to_string(st.max_angle_sigma_deg) + " (" + flange_figures(a, fa, axis) + "; " +
             flange_figures(b, fb, axis) + ")";
}

// A closed hem keeps its figures from the fits, but is listed as not measurable.
void mark_closed_hem(BendMeasurement& m, const SpringbackSettings& st) {
  if (m.nominal_angle_deg < st.hem_angle_deg) return;
  m.measurable = false;
  m.measured = false;
  m.status = "bend " + std::to_string(m.bend_id) + " not measurable: a closed hem (nominal " +
             std::to_string(m.nominal_angle_deg) +
             " deg), its folded flange lies on the sheet and a flange fit cannot tell its "
             "springback";
}

}  // namespace

// The signed angle from u to v about `axis`, from the full angle between them (degrees).
double turn_deg(const Vec3& u, const Vec3& v, const Vec3& axis) {
  const Vec3 c = u.cross(v);
  const double sine = c.dot(axis) < 0.0 ? -c.norm() : c.norm();
  return std::atan2(sine, u.dot(v)) * kRadToDeg;
}

// The flange's normal on the concave side of `bend` (the side facing the bend's centre of
// curvature), from where the flange's reference face lies relative to the bend axis: the
// concave side's face has the axis in front of it at the inner radius Ri >= 0, the convex
// side's face has it behind at Ri + t. The midway offset -t/2 decides, also for a sharp inner
// corner (Ri = 0) and for a surface model (t = 0, where Ri > 0). Never decided from the angle:
// at 90 degrees a normal and its opposite are equally near the nominal.
Vec3 concave_normal(const Flange& flange, const Bend& bend) {
  const Vec3 n = flange.normal.normalized();
  const double axis_offset = (bend.axis_point - flange.point).dot(n);
  return axis_offset >= -0.5 * flange.thickness_mm ? n : Vec3(-n);
}

namespace {

// The direction about which the sheet turns from flange a into flange b, so that the bend's
// turn is positive: the sheet leaves flange a towards the axis (in-plane, across the axis) and
// curves towards its concave side. From positions, not from na x nb, which vanishes for a
// closed hem (180 degrees) and would leave the sign of its springback to rounding.
Vec3 turn_axis(const Flange& fa, const Vec3& concave_a, const Bend& bend) {
  const Vec3 d = bend.axis_direction.normalized();
  Vec3 towards = bend.axis_point - fa.point;
  towards -= towards.dot(d) * d + towards.dot(concave_a) * concave_a;
  const Vec3 w = towards.cross(concave_a);
  return w.dot(d) < 0.0 ? Vec3(-d) : d;
}

}  // namespace

// An angle difference in (-180, 180]: near 180 degrees a measured turn of -179.99 is 180.01,
// so a closed hem that did not move has springback 0, not 359.99.
double wrapped_deg(double a) { return std::remainder(a, 360.0); }

BendMeasurement measure_bend(const Bend& bend, const Flange& fa, const Flange& fb,
                             const FlangeFit& a, const FlangeFit& b) {
  BendMeasurement m;
  m.bend_id = bend.id;
  m.flange_a = bend.flange_a;
  m.flange_b = bend.flange_b;
  m.face_ids = bend.face_ids;
  m.axis_point = bend.axis_point;
  m.radius_mm = bend.radius_mm;
  m.nominal_angle_deg = bend.nominal_angle_deg;
  // Both normals on the concave side of the sheet: the angle between them is the angle the
  // sheet turns.
  const Vec3 na = concave_normal(fa, bend), nb = concave_normal(fb, bend);
  m.axis_direction = turn_axis(fa, na, bend);
  if (!a.fitted || !b.fitted) {
    m.status =
        "bend " + std::to_string(bend.id) + " not measured: " + (a.fitted ? b.status : a.status);
    return m;
  }
  // Paper section 4: D = R_a R_b^-1 is how flange b lies relative to flange a in the data,
  // in the CAD frame; the measured bend angle is the angle between na and D nb (which equals
  // the angle between the two fitted planes, whatever either fit did about its own normal).
  const Mat3 D = relative_rotation_matrix(a.fit.T_model_subset, b.fit.T_model_subset);
  m.relative_rotation = axis_angle_of(D);
  const double nominal = turn_deg(na, nb, m.axis_direction);
  const double measured =
      measured_bend_angle_deg(na, nb, m.axis_direction, a.fit.T_model_subset, b.fit.T_model_subset);
  m.springback_deg = wrapped_deg(nominal - measured);
  m.measured_angle_deg = m.nominal_angle_deg - m.springback_deg;
  const Vec3 line = a.measured_normal.cross(b.measured_normal);
  m.measured_axis_direction =
      line.dot(m.axis_direction) < 0.0 ? -line.normalized() : line.normalized();
  m.plane_angle_deg = m.measured_angle_deg;
  m.measured = true;
  return m;
}

double measured_bend_angle_deg(const Vec3& normal_a, const Vec3& normal_b, const Vec3& axis,
                               const Transform& T_model_a, const Transform& T_model_b) {
  return turn_deg(normal_a, relative_rotation_matrix(T_model_a, T_model_b) * normal_b, axis);
}

Expected<SpringbackResult> measure_springback(const PartModel& model, const PointCloud& scan,
                                              const SpringbackSettings& st) {
  if (const std::string bad = check(model, st); !bad.empty())
    return fail("measure_springback: " + bad);
  const auto& seg = model.segmentation;
  SpringbackResult result;
  const auto cap = static_cast<std::size_t>(st.max_scan_points);
  result.thinning_stride = cap == 0 || scan.size() <= cap ? 1 : (scan.size() + cap - 1) / cap;
  result.points_used = (scan.size() + result.thinning_stride - 1) / result.thinning_stride;

  // 1. Label the model samples by flange, leaving out a margin around the bends, and by bend
  //    zone.
  const std::vector<double> margins = flange_margins(model, st);
  auto labels = sample_labels(model, margins, st.threads);
  const BendZones zones = label_bend_zones(model, labels);
  // 2. Assign the (thinned) scan points to flanges and zones by their nearest model sample;
  //    small flanges take more points from the full scan.
  const LocalFitTarget target(model);
  const auto order = thinned_in_space_order(scan, result.thinning_stride);
  auto assigned =
      assign_points(target, labels, seg.flanges.size() + zones.zones.size(), scan, order, st);
  add_dense_points(target, labels, scan, result.thinning_stride, st, assigned, seg.flanges.size());
  // 3. Fit each flange locally to the whole model.
  result.flanges = fit_flanges(target, scan, seg.flanges, assigned, st);
  for (std::size_t f = 0; f < seg.flanges.size(); ++f) result.flanges[f].margin_mm = margins[f];
  const double noise = median_fit_rms(result);
  // 4. Each bend from the relative rotation of its two flanges.
  const auto index_of = [&seg](int id) {
    const auto it = std::find_if(seg.flanges.begin(), seg.flanges.end(),
                                 [id](const Flange& f) { return f.id == id; });
    return static_cast<std::size_t>(it - seg.flanges.begin());
  };
  const auto bend_of = [&](const Bend& bend) {
    const std::size_t a = index_of(bend.flange_a), b = index_of(bend.flange_b);
    BendMeasurement m =
        measure_bend(bend, seg.flanges[a], seg.flanges[b], result.flanges[a], result.flanges[b]);
    check_angle_sigma(m, seg.flanges[a], seg.flanges[b], result.flanges[a], result.flanges[b],
                      noise, st);
    mark_closed_hem(m, st);
    return m;
  };
  for (const Bend& bend : seg.bends) result.bends.push_back(bend_of(bend));
  // 5. Beyond rigid flanges: flange shape, bend radius, the angle along each bend.
  const std::vector<std::vector<std::uint32_t>> zone_points(
      std::make_move_iterator(assigned.begin() + static_cast<std::ptrdiff_t>(seg.flanges.size())),
      std::make_move_iterator(assigned.end()));
  measure_shapes(model, scan, order, zones, zone_points, st.shape, st.threads, result);
  // 6. Fits that measure no plane of the scan: their bends again, now without an angle.
  const std::vector<int> rejected = reject_poor_fits(result, st);
  const auto touches = [&rejected](const Bend& bend) {
    return std::find(rejected.begin(), rejected.end(), bend.flange_a) != rejected.end() ||
           std::find(rejected.begin(), rejected.end(), bend.flange_b) != rejected.end();
  };
  for (std::size_t k = 0; k < seg.bends.size(); ++k)
    if (touches(seg.bends[k])) result.bends[k] = bend_of(seg.bends[k]);
  return result;
}

}  // namespace springscan::analysis
