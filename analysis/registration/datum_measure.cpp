// The datum features measured in the scan (datum.hpp step 1).
#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>

#include "analysis/registration/boundary.hpp"
#include "analysis/registration/datum_internal.hpp"

namespace springscan::analysis::datum_detail {
namespace {

constexpr double kWallNormal = 0.5;     // |n . axis| below this: a wall point (not a skin's)
constexpr double kSkinNormal = 0.8;     // n . normal above this: a point of the pad's skin
constexpr double kSkinMarginMm = 0.1;   // wall points this far inside the skins (their rims)
constexpr double kEdgeBandMm = 1.0;     // the band that locates an edge (boundary.hpp step 1)
constexpr std::size_t kEdgeSkip = 2;    // stray points beyond the edge
constexpr double kMadToSigma = 1.4826;  // median absolute deviation of a normal distribution
constexpr int kRobustRounds = 4;

double median_abs(std::vector<double> v) {
  if (v.empty()) return 0.0;
  for (double& x : v) x = std::abs(x);
  const auto mid = v.begin() + static_cast<long>(v.size() / 2);
  std::nth_element(v.begin(), mid, v.end());
  return *mid;
}

// Keeps the residuals within outlier_sigmas robust sigmas (never tighter than a micrometre, so
// that a noise-free test scan keeps its points).
std::vector<bool> inliers_of(const std::vector<double>& residuals, double sigmas) {
  const double limit = std::max(sigmas * kMadToSigma * median_abs(residuals), 1e-3);
  std::vector<bool> keep(residuals.size());
  for (std::size_t i = 0; i < residuals.size(); ++i) keep[i] = std::abs(residuals[i]) <= limit;
  return keep;
}

double rms_of(const std::vector<double>& residuals, const std::vector<bool>& keep,
              std::size_t& count) {
  double sum = 0.0;
  count = 0;
  for (std::size_t i = 0; i < residuals.size(); ++i)
    if (keep[i]) sum += residuals[i] * residuals[i], ++count;
  return count ? std::sqrt(sum / static_cast<double>(count)) : 0.0;
}

bool facing(const FeaturePoints& near, std::size_t i, const Vec3& n, double min_dot) {
  return near.normals.empty() || near.normals[i].dot(n) > min_dot;
}

bool on_wall(const FeaturePoints& near, std::size_t i, const Vec3& axis) {
  return near.normals.empty() || std::abs(near.normals[i].dot(axis)) < kWallNormal;
}

FeatureFit too_few(std::size_t n, const std::string& where, std::size_t need) {
  FeatureFit f;
  f.failure = std::to_string(n) + " scan points " + where + " (needs " + std::to_string(need) + ")";
  return f;
}

// ---- pad: a plane fit ------------------------------------------------------------------------

FeatureFit measure_pad(const Datum& d, const FeaturePoints& near, double band,
                       const DatumAlignmentSettings& s) {
  std::vector<Vec3> pts;
  for (std::size_t i = 0; i < near.points.size(); ++i) {
    const Vec3 v = near.points[i] - d.point;
    const double h = v.dot(d.normal);
    if (std::abs(h) <= band && (v - h * d.normal).norm() <= d.radius_mm &&
        facing(near, i, d.normal, kSkinNormal))
      pts.push_back(near.points[i]);
  }
  if (pts.size() < s.min_points) return too_few(pts.size(), "on the pad", s.min_points);
  std::vector<bool> keep(pts.size(), true);
  Vec3 centre = Vec3::Zero(), normal = d.normal;
  std::vector<double> res(pts.size());
  for (int round = 0; round < kRobustRounds; ++round) {
    centre.setZero();
    std::size_t n = 0;
    for (std::size_t i = 0; i < pts.size(); ++i)
      if (keep[i]) centre += pts[i], ++n;
    if (n < s.min_points) return too_few(n, "on the pad's plane", s.min_points);
    centre /= static_cast<double>(n);
    Mat3 cov = Mat3::Zero();
    for (std::size_t i = 0; i < pts.size(); ++i)
      if (keep[i]) cov += (pts[i] - centre) * (pts[i] - centre).transpose();
    normal = Eigen::SelfAdjointEigenSolver<Mat3>(cov).eigenvectors().col(0);
    if (normal.dot(d.normal) < 0.0) normal = -normal;
    for (std::size_t i = 0; i < pts.size(); ++i) res[i] = (pts[i] - centre).dot(normal);
    const auto next = inliers_of(res, s.outlier_sigmas);
    if (next == keep) break;
    keep = next;
  }
  FeatureFit f;
  f.measured = true;
  f.normal = normal;
  // Where the measured plane crosses the pad's normal line: what the pad fixes.
  f.point = d.point + (normal.dot(centre - d.point) / normal.dot(d.normal)) * d.normal;
  f.rms_mm = rms_of(res, keep, f.points);
  return f;
}

// ---- hole: a circle fit of the wall ----------------------------------------------------------

struct Circle {
  Eigen::Vector2d centre = Eigen::Vector2d::Zero();
  double radius = 0.0;
};

// The algebraic (Kasa) circle: least squares of x^2 + y^2 + D x + E y + F.
Circle kasa(const std::vector<Eigen::Vector2d>& p, const std::vector<bool>& keep) {
  Eigen::Matrix3d A = Eigen::Matrix3d::Zero();
  Eigen::Vector3d b = Eigen::Vector3d::Zero();
  for (std::size_t i = 0; i < p.size(); ++i) {
    if (!keep[i]) continue;
    const Eigen::Vector3d row(p[i].x(), p[i].y(), 1.0);
    A += row * row.transpose();
    b -= row * p[i].squaredNorm();
  }
  const Eigen::Vector3d x = A.ldlt().solve(b);
  Circle c;
  c.centre = -0.5 * x.head<2>();
  c.radius = std::sqrt(std::max(c.centre.squaredNorm() - x.z(), 0.0));
  return c;
}

// Geometric least squares of the distances to the circle, Gauss-Newton from `c`.
Circle geometric(const std::vector<Eigen::Vector2d>& p, const std::vector<bool>& keep, Circle c) {
  for (int it = 0; it < 20; ++it) {
    Eigen::Matrix3d A = Eigen::Matrix3d::Zero();
    Eigen::Vector3d b = Eigen::Vector3d::Zero();
    for (std::size_t i = 0; i < p.size(); ++i) {
      if (!keep[i]) continue;
      const Eigen::Vector2d v = p[i] - c.centre;
      const double rho = v.norm();
      if (rho < 1e-12) continue;
      const Eigen::Vector3d J(-v.x() / rho, -v.y() / rho, -1.0);
      A += J * J.transpose();
      b -= J * (rho - c.radius);
    }
    const Eigen::Vector3d step = A.ldlt().solve(b);
    if (!step.allFinite()) break;
    c.centre += step.head<2>();
    c.radius += step.z();
    if (step.norm() < 1e-10) break;
  }
  return c;
}

int sectors_seen(const std::vector<Eigen::Vector2d>& p, const std::vector<bool>& keep,
                 const Circle& c) {
  std::array<bool, 12> seen{};
  for (std::size_t i = 0; i < p.size(); ++i) {
    if (!keep[i]) continue;
    const Eigen::Vector2d v = p[i] - c.centre;
    const double a = std::atan2(v.y(), v.x()) + std::numbers::pi;
    seen[std::min<std::size_t>(11, static_cast<std::size_t>(a / (std::numbers::pi / 6.0)))] = true;
  }
  return static_cast<int>(std::count(seen.begin(), seen.end(), true));
}

// The hole from the in-plane points of its `seen` part ("wall" or "rim"): the robust circle
// (geometric least squares from the algebraic one, outliers beyond outlier_sigmas left out),
// seen over at least min_hole_sectors of 12; its centre in the plane of e1, e2 about d.point.
FeatureFit hole_from_circle_points(const Datum& d, const std::vector<Eigen::Vector2d>& pts,
                                   const Vec3& e1, const Vec3& e2, const std::string& seen,
                                   const DatumAlignmentSettings& s) {
  if (pts.size() < s.min_points) return too_few(pts.size(), "on the hole's " + seen, s.min_points);
  std::vector<bool> keep(pts.size(), true);
  Circle c;
  std::vector<double> res(pts.size());
  for (int round = 0; round < kRobustRounds; ++round) {
    c = geometric(pts, keep, round == 0 ? kasa(pts, keep) : c);
    for (std::size_t i = 0; i < pts.size(); ++i) res[i] = (pts[i] - c.centre).norm() - c.radius;
    const auto next = inliers_of(res, s.outlier_sigmas);
    if (next == keep) break;
    keep = next;
  }
  FeatureFit f;
  f.rms_mm = rms_of(res, keep, f.points);
  if (f.points < s.min_points) return too_few(f.points, "on the hole's circle", s.min_points);
  const int sectors = sectors_seen(pts, keep, c);
  if (sectors < s.min_hole_sectors) {
    f.failure = "its " + seen + " is seen over " + std::to_string(30 * sectors) +
                " deg only (needs " + std::to_string(30 * s.min_hole_sectors) + ")";
    return f;
  }
  f.measured = true;
  f.point = d.point + c.centre.x() * e1 + c.centre.y() * e2;
  f.diameter_mm = 2.0 * c.radius;
  return f;
}

// Wall points: between the two skins (clear of their rims), within `band` of the radius.
FeatureFit measure_hole(const Datum& d, const FeaturePoints& near, double band,
                        const DatumAlignmentSettings& s) {
  Vec3 e1, e2;
  complete_basis(d.normal, e1, e2);
  const double r0 = 0.5 * d.diameter_mm;
  std::vector<Eigen::Vector2d> pts;
  for (std::size_t i = 0; i < near.points.size(); ++i) {
    const Vec3 v = near.points[i] - d.point;
    const double h = v.dot(d.normal);
    const Eigen::Vector2d uv(v.dot(e1), v.dot(e2));
    if (h > -kSkinMarginMm || h < -d.thickness_mm + kSkinMarginMm) continue;
    if (std::abs(uv.norm() - r0) > band || !on_wall(near, i, d.normal)) continue;
    pts.push_back(uv);
  }
  return hole_from_circle_points(d, pts, e1, e2, "wall", s);
}

// A surface model's hole has no wall: its rim is where the skin's points stop. Per 5 deg
// sector of the annulus within `band` of the nominal circle, the innermost skin point is a rim
// point; the robust circle through them gives the centre, unbiased. Those points lie outside
// the true rim by about a radial gap of the sector's points (1 / (density x radius x sector
// angle) on average; the robust fit follows the nearer ones): the diameter comes out about
// 0.1-0.2 mm large at a laser's 11 points per mm^2, and is reported as measured.
FeatureFit measure_hole_rim(const Datum& d, const FeaturePoints& near, double band,
                            const DatumAlignmentSettings& s) {
  constexpr int kRimSectors = 72;
  constexpr double kSector = 2.0 * std::numbers::pi / kRimSectors;
  Vec3 e1, e2;
  complete_basis(d.normal, e1, e2);
  const double r0 = 0.5 * d.diameter_mm;
  const double outer = r0 + band;  // mm
  std::array<double, kRimSectors> inner;
  inner.fill(std::numeric_limits<double>::infinity());
  std::array<Eigen::Vector2d, kRimSectors> rim{};
  for (std::size_t i = 0; i < near.points.size(); ++i) {
    const Vec3 v = near.points[i] - d.point;
    if (std::abs(v.dot(d.normal)) > band || !facing(near, i, d.normal, kSkinNormal)) continue;
    const Eigen::Vector2d uv(v.dot(e1), v.dot(e2));
    const double rho = uv.norm();
    if (rho < r0 - band || rho > outer) continue;
    const double a = std::atan2(uv.y(), uv.x()) + std::numbers::pi;
    const auto k = std::min<std::size_t>(kRimSectors - 1, static_cast<std::size_t>(a / kSector));
    if (rho < inner[k]) inner[k] = rho, rim[k] = uv;
  }
  std::vector<Eigen::Vector2d> pts;
  for (int k = 0; k < kRimSectors; ++k)
    if (std::isfinite(inner[static_cast<std::size_t>(k)]))
      pts.push_back(rim[static_cast<std::size_t>(k)]);
  return hole_from_circle_points(d, pts, e1, e2, "rim", s);
}

// ---- slot: the mid-plane of its two straight walls -------------------------------------------

FeatureFit measure_slot(const Datum& d, const FeaturePoints& near, double band,
                        const DatumAlignmentSettings& s) {
  const Vec3 along = d.normal.cross(d.direction);
  const double half_width = 0.5 * d.diameter_mm;
  const double straight = 0.5 * (d.length_mm - d.diameter_mm);  // the walls' half length
  std::array<std::vector<double>, 2> side;                      // across-positions of the -/+ wall
  for (std::size_t i = 0; i < near.points.size(); ++i) {
    const Vec3 v = near.points[i] - d.point;
    const double h = v.dot(d.normal), a = v.dot(along), u = v.dot(d.direction);
    if (h > -kSkinMarginMm || h < -d.thickness_mm + kSkinMarginMm || std::abs(a) > straight)
      continue;
    if (std::abs(std::abs(u) - half_width) > band || !on_wall(near, i, d.normal)) continue;
    side[u > 0.0 ? 1 : 0].push_back(u);
  }
  FeatureFit f;
  double position[2];
  std::vector<double> res;
  std::vector<bool> all;
  for (int k = 0; k < 2; ++k) {
    auto& u = side[static_cast<std::size_t>(k)];
    if (u.size() < s.min_points / 2)
      return too_few(u.size(), k ? "on the slot's + wall" : "on the slot's - wall",
                     s.min_points / 2);
    // A robust mean: the median, then the mean of the points within outlier_sigmas.
    std::vector<double> sorted = u;
    std::nth_element(sorted.begin(), sorted.begin() + static_cast<long>(sorted.size() / 2),
                     sorted.end());
    const double median = sorted[sorted.size() / 2];
    std::vector<double> r(u.size());
    for (std::size_t i = 0; i < u.size(); ++i) r[i] = u[i] - median;
    const auto keep = inliers_of(r, s.outlier_sigmas);
    double sum = 0.0;
    std::size_t n = 0;
    for (std::size_t i = 0; i < u.size(); ++i)
      if (keep[i]) sum += u[i], ++n;
    position[k] = sum / static_cast<double>(n);
    for (std::size_t i = 0; i < u.size(); ++i) res.push_back(u[i] - position[k]);
    all.insert(all.end(), keep.begin(), keep.end());
  }
  f.measured = true;
  f.point = d.point + 0.5 * (position[0] + position[1]) * d.direction;
  f.diameter_mm = position[1] - position[0];
  f.rms_mm = rms_of(res, all, f.points);
  return f;
}

// ---- edge: the band estimate of the skin's end -----------------------------------------------

FeatureFit measure_edge(const Datum& d, const FeaturePoints& near, double band,
                        const DatumAlignmentSettings& s) {
  const Vec3 along = d.normal.cross(d.direction);
  std::vector<double> u;
  for (std::size_t i = 0; i < near.points.size(); ++i) {
    const Vec3 v = near.points[i] - d.point;
    const double h = v.dot(d.normal), a = v.dot(along), across = v.dot(d.direction);
    if (std::abs(h) > band || std::abs(a) > d.radius_mm) continue;
    if (across < -(band + 2.0 * kEdgeBandMm) || !facing(near, i, d.normal, kSkinNormal)) continue;
    u.push_back(across);
  }
  const auto end = high_end(u, kEdgeBandMm, s.min_points, kEdgeSkip);
  if (!end) return too_few(u.size(), "on the skin at the edge", s.min_points + kEdgeSkip);
  FeatureFit f;
  f.measured = true;
  f.point = d.point + *end * d.direction;
  f.points = u.size();
  return f;
}

}  // namespace

void complete_basis(const Vec3& n, Vec3& e1, Vec3& e2) {
  const Vec3 seed = std::abs(n.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY();
  e1 = (seed - seed.dot(n) * n).normalized();
  e2 = n.cross(e1);
}

std::vector<Vec3> fixed_directions(const Datum& d) {
  if (d.kind == DatumKind::kPad) return {d.normal};
  if (d.kind == DatumKind::kHole && d.direction.isZero()) {
    Vec3 e1, e2;
    complete_basis(d.normal, e1, e2);
    return {e1, e2};
  }
  return {d.direction};
}

double gather_radius(const Datum& d, double band_mm) {
  const double wall = d.thickness_mm + band_mm;
  switch (d.kind) {
    case DatumKind::kPad:
      return std::hypot(d.radius_mm, band_mm);
    case DatumKind::kHole:
      return std::hypot(0.5 * d.diameter_mm + band_mm, wall);
    case DatumKind::kSlot:
      return std::hypot(0.5 * d.length_mm + band_mm, wall);
    case DatumKind::kEdge:
      return std::hypot(d.radius_mm, band_mm + 2.0 * kEdgeBandMm, band_mm);
  }
  return 0.0;
}

FeatureFit measure_feature(const Datum& d, const FeaturePoints& near, double band_mm,
                           const DatumAlignmentSettings& s) {
  // A skin's band never reaches the sheet's other skin.
  const double skin_band =
      d.thickness_mm > 0.0 ? std::min(band_mm, 0.45 * d.thickness_mm) : band_mm;
  switch (d.kind) {
    case DatumKind::kPad:
      return measure_pad(d, near, skin_band, s);
    case DatumKind::kHole:
      // A surface model (no thickness) has no wall: the rim of its skin.
      return d.thickness_mm > 0.0 ? measure_hole(d, near, band_mm, s)
                                  : measure_hole_rim(d, near, skin_band, s);
    case DatumKind::kSlot:
      return measure_slot(d, near, band_mm, s);
    case DatumKind::kEdge:
      return measure_edge(d, near, skin_band, s);
  }
  return {};
}

}  // namespace springscan::analysis::datum_detail
