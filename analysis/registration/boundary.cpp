// The part's boundary in the global fit (boundary.hpp).
#include "analysis/registration/boundary.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <random>

#include "analysis/core/parallel.hpp"
#include "analysis/core/spatial_order.hpp"

namespace springscan::analysis {
namespace {

constexpr double kFacingAlong = 0.5;  // |n . u| above this: the face looks along u
constexpr int kMaxPasses = 3;         // ends re-located after each shift (see pin_direction)
constexpr double kConvergedMm = 1e-3;
constexpr std::size_t kSkipOutermost = 2;  // stray scan points on the surface beyond the end

std::optional<Error> check(const BoundarySettings& s) {
  if (!(s.free_eigenvalue_ratio > 0.0 && s.free_eigenvalue_ratio < 1.0))
    return fail(ErrorCode::kInvalidSettings, "boundary: free_eigenvalue_ratio must be in (0, 1)");
  if (!(s.end_band_mm > 0.0) || !(s.surface_distance_mm > 0.0) || !(s.cover_tolerance_mm >= 0.0))
    return fail(ErrorCode::kInvalidSettings,
                "boundary: end_band_mm and surface_distance_mm must be > 0, "
                "cover_tolerance_mm >= 0");
  if (s.info_points == 0 || s.scan_points == 0 || s.model_points == 0 || s.min_band_points < 2)
    return fail(ErrorCode::kInvalidSettings, "boundary: point counts must be positive");
  return std::nullopt;
}

// Even samples of the tessellation (area-weighted, fixed seed, so a result is reproducible),
// with their triangle's normal; the model's samples when there is no tessellation. Built once
// per model and sample count (PartModel::tessellation_samples).
PointCloud sample_surface(const PartModel& model, std::size_t count) {
  const TriangleMesh& mesh = model.mesh;
  PointCloud out;
  if (mesh.triangles.empty()) {
    out.points = model.samples.points;
    out.normals = model.samples.normals;
    return out;
  }
  std::vector<double> cumulative;
  cumulative.reserve(mesh.triangles.size());
  double total = 0.0;
  for (const auto& t : mesh.triangles) {
    const Vec3 &a = mesh.vertices[t[0]], &b = mesh.vertices[t[1]], &c = mesh.vertices[t[2]];
    total += 0.5 * (b - a).cross(c - a).norm();
    cumulative.push_back(total);
  }
  if (!(total > 0.0)) {
    out.points = model.samples.points;
    out.normals = model.samples.normals;
    return out;
  }
  out.points.reserve(count);
  out.normals.reserve(count);
  std::mt19937_64 rng(0x5eed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (std::size_t i = 0; i < count; ++i) {
    const double at = unit(rng) * total;
    const auto k = static_cast<std::size_t>(
        std::lower_bound(cumulative.begin(), cumulative.end(), at) - cumulative.begin());
    const auto& t = mesh.triangles[std::min(k, mesh.triangles.size() - 1)];
    const Vec3 &a = mesh.vertices[t[0]], &b = mesh.vertices[t[1]], &c = mesh.vertices[t[2]];
    const double r1 = std::sqrt(unit(rng)), r2 = unit(rng);
    out.points.push_back((1.0 - r1) * a + r1 * (1.0 - r2) * b + r1 * r2 * c);
    const Vec3 n = (b - a).cross(c - a);
    out.normals.push_back(n.norm() > 0.0 ? Vec3(n.normalized()) : Vec3::UnitZ());
  }
  return out;
}

std::shared_ptr<const PointCloud> model_surface(const PartModel& model, std::size_t count) {
  return model.tessellation_samples.get(count, [&] { return sample_surface(model, count); });
}

// Distance of q to the model's surface near its nearest sample (along that sample's normal),
// and the sample's normal.
struct SurfaceContact {
  double distance_mm = std::numeric_limits<double>::infinity();
  Vec3 normal = Vec3::Zero();
};

SurfaceContact contact(const Vec3& q, const KdTree& tree, const std::vector<Vec3>& normals) {
  const auto near = tree.nearest(q);
  if (!near) return {};
  const Vec3& n = normals[near->index];
  return {std::abs((q - tree.points()[near->index]).dot(n)), n};
}

// Directions the scan's surface does not constrain: eigenvectors of sum n n^T (over scan
// points on the surface) whose eigenvalue is below ratio x the largest.
std::vector<Vec3> free_translations(const std::vector<Vec3>& scan_cad, const KdTree& tree,
                                    const std::vector<Vec3>& normals, const BoundarySettings& s) {
  const std::vector<Vec3> points = strided_sample(scan_cad, s.info_points);
  const std::vector<std::uint32_t> order = search_order(points, s.threads);
  std::vector<SurfaceContact> contacts(points.size());
  parallel_blocks(points.size(), s.threads, [&](std::size_t, std::size_t begin, std::size_t end) {
    for (std::size_t k = begin; k < end; ++k)
      contacts[order[k]] = contact(points[order[k]], tree, normals);
  });
  Mat3 info = Mat3::Zero();
  for (const SurfaceContact& c : contacts)  // in the sample's order: the sum does not depend
    if (c.distance_mm <= s.surface_distance_mm) info += c.normal * c.normal.transpose();
  std::vector<Vec3> out;
  const Eigen::SelfAdjointEigenSolver<Mat3> eig(info);
  const double largest = eig.eigenvalues().maxCoeff();
  if (!(largest > 0.0)) return out;
  for (int k = 0; k < 3; ++k)
    if (eig.eigenvalues()(k) < s.free_eigenvalue_ratio * largest)
      out.push_back(eig.eigenvectors().col(k).normalized());
  return out;
}

struct Extent {
  std::optional<double> low, high;
  bool located() const { return low && high; }
  double length() const { return *high - *low; }
  double centre() const { return 0.5 * (*low + *high); }
};

Extent extent_of(std::vector<double> values, const BoundarySettings& s) {
  Extent e;
  e.high = high_end(values, s.end_band_mm, s.min_band_points, 0);
  for (double& v : values) v = -v;
  if (auto low = high_end(values, s.end_band_mm, s.min_band_points, 0)) e.low = -*low;
  return e;
}

// The model's extent along u over the faces that do not look along u.
Extent model_extent(const PointCloud& model, const Vec3& u, const BoundarySettings& s) {
  std::vector<double> values;
  values.reserve(model.points.size());
  for (std::size_t i = 0; i < model.points.size(); ++i)
    if (std::abs(model.normals[i].dot(u)) <= kFacingAlong) values.push_back(u.dot(model.points[i]));
  return extent_of(std::move(values), s);
}

// The scan's extent along u over its points on the surface. With a `window`, only points within
// it of the model's ends are looked at (the nearest-sample queries are the cost). The queries
// run on s.threads threads in space order; the ends are taken from the points in their order.
Extent scan_extent(const BoundaryScan& scan, const Transform& T, const KdTree& tree,
                   const std::vector<Vec3>& normals, const Vec3& u, const Extent& model,
                   const BoundarySettings& s, double window) {
  constexpr std::uint8_t kHigh = 1, kLow = 2;
  const std::vector<Vec3>& points = scan.ordered();
  const std::vector<std::uint32_t>& index = scan.index();
  std::vector<std::uint8_t> near(points.size(), 0);  // kHigh | kLow, 0: not used
  std::vector<double> along(points.size());
  parallel_blocks(points.size(), s.threads, [&](std::size_t, std::size_t begin, std::size_t end) {
    for (std::size_t k = begin; k < end; ++k) {
      const std::uint32_t i = index[k];
      const Vec3 q = T * points[k];
      const double v = u.dot(q);
      const bool near_high = v >= *model.high - window, near_low = v <= *model.low + window;
      if (!near_high && !near_low) continue;
      // As on the model's side, points on faces that look along u are left out:
      // a solid's end face (a wall's outer skin, a sheet's edge) seen at a slant
      // piles its points up at the end, and the band's mean would place the end
      // up to a band width too far out.
      const SurfaceContact c = contact(q, tree, normals);
      if (c.distance_mm > s.surface_distance_mm || std::abs(c.normal.dot(u)) > kFacingAlong)
        continue;
      along[i] = v;
      near[i] = static_cast<std::uint8_t>((near_high ? kHigh : 0) | (near_low ? kLow : 0));
    }
  });
  std::vector<double> high, low;
  for (std::size_t i = 0; i < near.size(); ++i) {
    if (near[i] & kHigh) high.push_back(along[i]);
    if (near[i] & kLow) low.push_back(along[i]);
  }
  Extent e;
  e.high = high_end(high, s.end_band_mm, s.min_band_points, kSkipOutermost);
  for (double& v : low) v = -v;
  if (auto end = high_end(low, s.end_band_mm, s.min_band_points, kSkipOutermost)) e.low = -*end;
  return e;
}

std::string mm(double v) {
  char text[32];
  std::snprintf(text, sizeof text, "%.2f mm", v);
  return text;
}

// Locates both ends of scan and model along u and moves the fit to match them (boundary.hpp
// step 2), repeated while the shift changes: points past the model's end only count once the
// fit has brought them onto the surface.
FreeDirection pin_direction(const BoundaryScan& scan, Transform& T, const KdTree& tree,
                            const std::vector<Vec3>& normals, const PointCloud& model,
                            const Vec3& u, const BoundarySettings& s) {
  FreeDirection d;
  d.direction = u;
  const Extent m = model_extent(model, u, s);
  if (!m.located()) {
    d.rule = "free: the model's ends along it could not be located";
    return d;
  }
  d.model_length_mm = m.length();
  for (int pass = 0; pass < kMaxPasses; ++pass) {
    Extent e = scan_extent(scan, T, tree, normals, u, m, s, s.end_search_mm + 2.0 * s.end_band_mm);
    // No scan near an end of the model: the scan's ends lie farther in (or out); all its points.
    if (!e.located())
      e = scan_extent(scan, T, tree, normals, u, m, s, std::numeric_limits<double>::infinity());
    if (!e.located()) {
      d.rule = "free: the scan's ends along it could not be located (too few points)";
      return d;
    }
    d.scan_length_mm = e.length();
    if (e.length() < m.length() - s.cover_tolerance_mm) {
      d.pinned = false;
      d.rule = "free: the scan spans " + mm(e.length()) + " of the model's " + mm(m.length()) +
               " along it; the position along it is the surface fit's and arbitrary";
      return d;
    }
    if (!s.pin_free_directions) {
      d.rule = "free: pinning is off (registration settings)";
      return d;
    }
    const double shift = m.centre() - e.centre();
    T.pretranslate(shift * u);
    d.shift_mm += shift;
    d.pinned = true;
    d.rule = e.length() > m.length() + s.cover_tolerance_mm
                 ? "centred: the scan spans " + mm(e.length()) + ", more than the model's " +
                       mm(m.length()) + " (extra material or a fixture in the scan?)"
                 : "pinned by the part's ends: scan " + mm(e.length()) + ", model " +
                       mm(m.length()) + " end to end";
    if (std::abs(shift) < kConvergedMm) break;
  }
  return d;
}

}  // namespace

std::optional<double> high_end(std::vector<double>& values, double band_mm, std::size_t min_points,
                               std::size_t skip_outermost) {
  if (values.size() < min_points + skip_outermost) return std::nullopt;
  // The outermost value after the `skip_outermost` largest (stray points on the surface's
  // extension beyond the end).
  std::nth_element(values.begin(), values.begin() + static_cast<long>(skip_outermost), values.end(),
                   std::greater<>());
  const double e0 = values[skip_outermost];
  double sum = 0.0;
  std::size_t n = 0;
  for (double v : values)
    if (v >= e0 - band_mm && v <= e0) sum += v, ++n;
  if (n < min_points) return std::nullopt;
  return 2.0 * (sum / static_cast<double>(n)) - e0 + band_mm;
}

BoundaryScan::BoundaryScan(const std::vector<Vec3>& scan, const BoundarySettings& settings)
    : scan_(&scan),
      info_points_(settings.info_points),
      scan_points_(settings.scan_points),
      threads_(settings.threads),
      info_(strided_sample(scan, settings.info_points)) {}

bool BoundaryScan::fits(const BoundarySettings& settings) const {
  return settings.info_points == info_points_ && settings.scan_points == scan_points_ &&
         settings.threads == threads_;
}

const std::vector<Vec3>& BoundaryScan::ordered() const {
  build();
  return ordered_;
}

const std::vector<std::uint32_t>& BoundaryScan::index() const {
  build();
  return index_;
}

// The large sample gathered in search order once: the extent's queries then read it in order,
// not at random over 200,000 points.
void BoundaryScan::build() const {
  if (!ordered_.empty() || scan_->empty()) return;
  const std::vector<Vec3> sample = strided_sample(*scan_, scan_points_);
  index_ = search_order(sample, threads_);
  ordered_.resize(sample.size());
  for (std::size_t k = 0; k < sample.size(); ++k) ordered_[k] = sample[index_[k]];
}

Expected<BoundaryResult> pin_to_boundary(const std::vector<Vec3>& scan, const Transform& T_cad_scan,
                                         const PartModel& model, const KdTree& model_tree,
                                         const BoundarySettings& settings) {
  return pin_to_boundary(BoundaryScan(scan, settings), T_cad_scan, model, model_tree, settings);
}

Expected<BoundaryResult> pin_to_boundary(const BoundaryScan& scan, const Transform& T_cad_scan,
                                         const PartModel& model, const KdTree& model_tree,
                                         const BoundarySettings& settings) {
  if (auto error = check(settings)) return *error;
  if (!scan.fits(settings))
    return pin_to_boundary(scan.scan(), T_cad_scan, model, model_tree, settings);
  if (scan.scan().empty()) return fail("boundary: the scan is empty");
  if (model_tree.empty() || model.samples.normals.size() != model_tree.size())
    return fail("boundary: the model has no samples with normals");
  BoundaryResult out;
  out.T_cad_scan = T_cad_scan;
  const std::vector<Vec3>& normals = model.samples.normals;
  std::vector<Vec3> info_scan = scan.info();
  for (Vec3& p : info_scan) p = T_cad_scan * p;
  const std::vector<Vec3> free = free_translations(info_scan, model_tree, normals, settings);
  if (free.empty()) return out;
  const std::shared_ptr<const PointCloud> surface = model_surface(model, settings.model_points);
  for (const Vec3& u : free)
    out.free_directions.push_back(
        pin_direction(scan, out.T_cad_scan, model_tree, normals, *surface, u, settings));
  return out;
}

}  // namespace springscan::analysis
