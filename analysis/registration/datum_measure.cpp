// The datum features measured in the scan (datum.hpp step 1).
#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <optional>

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
constexpr double kNone = std::numeric_limits<double>::infinity();  // no point in a stretch
constexpr std::size_t kRimSectors = 24;  // a hole's rim: sectors of 15 deg
constexpr double kRimReachMm = 3.0;      // the skin around a rim is gathered this far out

// A skin's band never reaches the sheet's other skin.
double skin_band_of(const Datum& d, double band_mm) {
  return d.thickness_mm > 0.0 ? std::min(band_mm, 0.45 * d.thickness_mm) : band_mm;
}

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
  f.measured_by = "plane";
  f.normal = normal;
  // Where the measured plane crosses the pad's normal line: what the pad fixes.
  f.point = d.point + (normal.dot(centre - d.point) / normal.dot(d.normal)) * d.normal;
  f.rms_mm = rms_of(res, keep, f.points);
  return f;
}

// ---- hole: circles of its wall and of its rim on the seen skin -------------------------------

using Vec2 = Eigen::Vector2d;

struct Circle {
  Vec2 centre = Vec2::Zero();
  double radius = 0.0;
};

// The algebraic (Kasa) circle: least squares of x^2 + y^2 + D x + E y + F.
Circle kasa(const std::vector<Vec2>& p, const std::vector<bool>& keep) {
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

// The normal matrix of the geometric fit's distances at `c` (centre x, y, radius), each point's
// distance weighted by `weight` (the inverse of its variance; none: 1).
Eigen::Matrix3d circle_normal_matrix(const std::vector<Vec2>& p, const std::vector<bool>& keep,
                                     const Circle& c, Eigen::Vector3d* b = nullptr,
                                     const std::vector<double>* weight = nullptr) {
  Eigen::Matrix3d A = Eigen::Matrix3d::Zero();
  if (b) b->setZero();
  for (std::size_t i = 0; i < p.size(); ++i) {
    if (!keep[i]) continue;
    const Vec2 v = p[i] - c.centre;
    const double rho = v.norm();
    if (rho < 1e-12) continue;
    const double w = weight ? (*weight)[i] : 1.0;
    const Eigen::Vector3d J(-v.x() / rho, -v.y() / rho, -1.0);
    A += w * J * J.transpose();
    if (b) *b -= w * J * (rho - c.radius);
  }
  return A;
}

// Geometric least squares of the (weighted) distances to the circle, Gauss-Newton from `c`.
Circle geometric(const std::vector<Vec2>& p, const std::vector<bool>& keep, Circle c,
                 const std::vector<double>* weight = nullptr) {
  for (int it = 0; it < 20; ++it) {
    Eigen::Vector3d b;
    const Eigen::Matrix3d A = circle_normal_matrix(p, keep, c, &b, weight);
    const Eigen::Vector3d step = A.ldlt().solve(b);
    if (!step.allFinite()) break;
    c.centre += step.head<2>();
    c.radius += step.z();
    if (step.norm() < 1e-10) break;
  }
  return c;
}

int sectors_seen(const std::vector<Vec2>& p, const std::vector<bool>& keep, const Circle& c) {
  std::array<bool, 12> seen{};
  for (std::size_t i = 0; i < p.size(); ++i) {
    if (!keep[i]) continue;
    const Vec2 v = p[i] - c.centre;
    const double a = std::atan2(v.y(), v.x()) + std::numbers::pi;
    seen[std::min<std::size_t>(11, static_cast<std::size_t>(a / (std::numbers::pi / 6.0)))] = true;
  }
  return static_cast<int>(std::count(seen.begin(), seen.end(), true));
}

// One robust circle (geometric least squares from the algebraic one, outliers beyond
// outlier_sigmas left out) and what it is worth: the information of its centre (the inverse of
// its covariance, rms^2 x the normal matrix's inverse), the 30 deg sectors it covers.
struct CircleFit {
  bool fitted = false;
  Circle circle;
  Eigen::Matrix2d information = Eigen::Matrix2d::Zero();  // 1 / mm^2
  std::size_t points = 0;
  double rms = 0.0;
  int sectors = 0;
  std::string failure;
};

// A scan's noise is not the same in every direction of the hole's plane: a tilted laser's lies
// along its rays, whose part in the plane has one direction, so a one-sided view's wall points
// seen across that direction are sharper than those seen along it, and the centre across it is
// fixed by them (the cover flange's 3.8 mm holes, sigma 0.05: the wall's centre 0.0049 mm rms
// across, 0.0069 along, where its rms distance said 0.004 either way). With enough points the
// residuals' variance is fitted as u^T S u over each point's direction u from the centre (S a 2 x
// 2 covariance, its smaller axis at least kMinVarianceRatio of its larger: a few points never
// dominate), and the circle refitted with each point weighted by its inverse, outliers judged
// by their weighted residuals; the centre's covariance is then that fit's own.
constexpr std::size_t kDirectionalPoints = 48;
constexpr double kMinVarianceRatio = 0.1;

void directional_refit(const std::vector<Vec2>& pts, const DatumAlignmentSettings& s,
                       CircleFit& out, std::vector<bool> keep, Eigen::Matrix3d& cov) {
  std::vector<double> weight(pts.size(), 1.0), res(pts.size());
  Circle c = out.circle;
  for (int round = 0; round < 2; ++round) {
    Eigen::Matrix3d A = Eigen::Matrix3d::Zero();
    Eigen::Vector3d b = Eigen::Vector3d::Zero();
    for (std::size_t i = 0; i < pts.size(); ++i) {
      if (!keep[i]) continue;
      const Vec2 u = (pts[i] - c.centre).normalized();
      const double r = (pts[i] - c.centre).norm() - c.radius;
      const Eigen::Vector3d row(u.x() * u.x(), u.y() * u.y(), 2.0 * u.x() * u.y());
      A += row * row.transpose();
      b += row * r * r;
    }
    const Eigen::Vector3d v = A.ldlt().solve(b);
    if (!v.allFinite()) return;
    Eigen::Matrix2d S;
    S << v.x(), v.z(), v.z(), v.y();
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(S);
    const double top = std::max(eig.eigenvalues().maxCoeff(), 1e-6);
    const Eigen::Vector2d lambda = eig.eigenvalues().cwiseMax(kMinVarianceRatio * top);
    S = eig.eigenvectors() * lambda.asDiagonal() * eig.eigenvectors().transpose();
    for (std::size_t i = 0; i < pts.size(); ++i) {
      const Vec2 u = (pts[i] - c.centre).normalized();
      weight[i] = 1.0 / (u.transpose() * S * u);
    }
    c = geometric(pts, keep, c, &weight);
    for (std::size_t i = 0; i < pts.size(); ++i)
      res[i] = ((pts[i] - c.centre).norm() - c.radius) * std::sqrt(weight[i]);
    keep = inliers_of(res, s.outlier_sigmas);
  }
  const Eigen::Matrix3d info = circle_normal_matrix(pts, keep, c, nullptr, &weight);
  const Eigen::Matrix3d next = info.inverse();
  if (!next.allFinite() ||
      std::count(keep.begin(), keep.end(), true) < static_cast<long>(s.min_points))
    return;
  out.circle = c;
  cov = next;
}

CircleFit robust_circle(const std::vector<Vec2>& pts, const std::string& seen,
                        const DatumAlignmentSettings& s) {
  CircleFit out;
  if (pts.size() < s.min_points) {
    out.failure = too_few(pts.size(), "on the hole's " + seen, s.min_points).failure;
    return out;
  }
  std::vector<bool> keep(pts.size(), true);
  std::vector<double> res(pts.size());
  for (int round = 0; round < kRobustRounds; ++round) {
    out.circle = geometric(pts, keep, round == 0 ? kasa(pts, keep) : out.circle);
    for (std::size_t i = 0; i < pts.size(); ++i)
      res[i] = (pts[i] - out.circle.centre).norm() - out.circle.radius;
    const auto next = inliers_of(res, s.outlier_sigmas);
    if (next == keep) break;
    keep = next;
  }
  out.rms = rms_of(res, keep, out.points);
  if (out.points < s.min_points) {
    out.failure = too_few(out.points, "on the hole's " + seen + " circle", s.min_points).failure;
    return out;
  }
  out.sectors = sectors_seen(pts, keep, out.circle);
  Eigen::Matrix3d cov =
      circle_normal_matrix(pts, keep, out.circle).inverse() * std::max(out.rms * out.rms, 1e-6);
  if (out.points >= kDirectionalPoints) directional_refit(pts, s, out, keep, cov);
  out.information = cov.topLeftCorner<2, 2>().inverse();
  out.fitted = out.information.allFinite();
  return out;
}

// The rim of an outline on the seen skin from the skin's points beyond it: per stretch of the
// outline `arc` mm long, the innermost point lies beyond the rim by a gap, and the mean gap is
// taken off. An even random spread of points (density 1 / spacing^2) gives 1 / (density x arc);
// a laser's lines do not (points in rows: smaller gaps, by the rows' direction to the rim; a
// sparse scan of a bracket's 6 mm hole came out 0.4 mm small by the model). So the mean gap is
// measured on the seen skin itself (skin_gap), the model only where too little skin is seen.
double rim_gap_mean(double spacing, double arc) { return spacing * spacing / arc; }

// The gap measured: the same innermost rule at a line kGapLineMm beyond the outline, inside the
// whole skin around it. Each skin point by how far beyond the outline it lies and the stretch
// (of the rims' length) it is in.
struct GapSample {
  double beyond = 0.0;
  std::size_t stretch = 0;
};
constexpr double kGapLineMm = 1.0;
constexpr std::size_t kGapStretchesNeeded = 6;

// The mean over stretches with skin on both sides of the line of the first point's distance
// past it (within `reach`); `fallback` where fewer than kGapStretchesNeeded such stretches.
double skin_gap(const std::vector<GapSample>& samples, std::size_t stretches, double reach,
                double fallback) {
  std::vector<double> first(stretches, kNone);
  std::vector<char> skin_before(stretches, 0);
  for (const GapSample& g : samples) {
    if (g.stretch >= stretches) continue;
    if (g.beyond < kGapLineMm) {
      // The skin between the rim's reach and the line: the stretch lies in whole skin.
      if (g.beyond >= 0.5 * kGapLineMm) skin_before[g.stretch] = 1;
    } else if (g.beyond <= kGapLineMm + reach) {
      first[g.stretch] = std::min(first[g.stretch], g.beyond - kGapLineMm);
    }
  }
  double sum = 0.0;
  std::size_t n = 0;
  for (std::size_t k = 0; k < stretches; ++k)
    if (skin_before[k] && first[k] != kNone) sum += first[k], ++n;
  return n >= kGapStretchesNeeded ? sum / static_cast<double>(n) : fallback;
}

// The rim of a hole: per sector (kRimSectors), the innermost skin point within band of it, at
// its radius less the mean gap (measured at a circle kGapLineMm outside, in sectors of the same
// arc; `reach` beyond it).
std::vector<Vec2> rim_points(const Datum& d, const FeaturePoints& near, double band, double gap,
                             double spacing, const Vec3& e1, const Vec3& e2) {
  const double r0 = 0.5 * d.diameter_mm;
  const double width = 2.0 * std::numbers::pi / kRimSectors;
  const double arc = width * r0;
  const double r_line = r0 + kGapLineMm;
  const auto line_sectors = static_cast<std::size_t>(2.0 * std::numbers::pi * r_line / arc);
  const double reach = std::min(gap, kRimReachMm - kGapLineMm);
  std::array<double, kRimSectors> inner;
  inner.fill(std::numeric_limits<double>::infinity());
  std::array<Vec2, kRimSectors> rim{};
  std::vector<GapSample> samples;
  // Without normals a solid's wall points just under the rim would count as the skin's: the skin
  // band narrowed to the wall points' margin.
  const double skin =
      near.normals.empty() && d.thickness_mm > 0.0 ? std::min(band, kSkinMarginMm) : band;
  for (std::size_t i = 0; i < near.points.size(); ++i) {
    const Vec3 v = near.points[i] - d.point;
    if (std::abs(v.dot(d.normal)) > skin || !facing(near, i, d.normal, kSkinNormal)) continue;
    const Vec2 uv(v.dot(e1), v.dot(e2));
    const double rho = uv.norm();
    if (rho < r0 - band) continue;
    const double a = std::atan2(uv.y(), uv.x()) + std::numbers::pi;
    if (rho >= r0 + 0.5 * kGapLineMm && rho <= r_line + reach && line_sectors > 0)
      samples.push_back(
          {rho - r0, std::min(line_sectors - 1,
                              static_cast<std::size_t>(a / (2.0 * std::numbers::pi) *
                                                       static_cast<double>(line_sectors)))});
    if (rho > r0 + band + gap) continue;
    const auto k = std::min<std::size_t>(kRimSectors - 1, static_cast<std::size_t>(a / width));
    if (rho < inner[k]) inner[k] = rho, rim[k] = uv;
  }
  const double mean_gap = skin_gap(samples, line_sectors, reach, rim_gap_mean(spacing, arc));
  std::vector<Vec2> pts;
  for (std::size_t k = 0; k < kRimSectors; ++k)
    if (std::isfinite(inner[k])) pts.push_back(rim[k] * (1.0 - mean_gap / inner[k]));
  return pts;
}

// Wall points: between the two skins (clear of their rims), within `band` of the radius.
std::vector<Vec2> wall_points(const Datum& d, const FeaturePoints& near, double band,
                              const Vec3& e1, const Vec3& e2) {
  const double r0 = 0.5 * d.diameter_mm;
  std::vector<Vec2> pts;
  for (std::size_t i = 0; i < near.points.size(); ++i) {
    const Vec3 v = near.points[i] - d.point;
    const double h = v.dot(d.normal);
    const Vec2 uv(v.dot(e1), v.dot(e2));
    if (h > -kSkinMarginMm || h < -d.thickness_mm + kSkinMarginMm) continue;
    if (std::abs(uv.norm() - r0) > band || !on_wall(near, i, d.normal)) continue;
    pts.push_back(uv);
  }
  return pts;
}

// The rim's reach past the nominal: kRimGapSpacings point spacings (at least kRimGapMinMm).
constexpr double kRimGapSpacings = 4.0;
constexpr double kRimGapMinMm = 0.3;
constexpr int kPartialWallSectors = 4;  // a wall of 120 deg still adds to a rim
constexpr int kRimSectorsNeeded = 9;    // a rim (seen all round on the seen skin) over 270 deg
// A circle this much wider or narrower than the hole (or 5 %) is something else: a sheet's
// edge through the search band, another hole.
constexpr double kDiameterToleranceMm = 0.3;

double rim_gap(const Datum& d, const FeaturePoints& near, double skin_band, double& spacing) {
  // Beyond the whole outline: a slot's reaches half its length from its centre.
  const double r0 = 0.5 * (d.kind == DatumKind::kSlot ? d.length_mm : d.diameter_mm);
  spacing = skin_spacing(d, near, skin_band, r0 + 1.0, r0 + kRimReachMm);
  return std::max(kRimGapSpacings * spacing, kRimGapMinMm);
}

FeatureFit from_circle(const Datum& d, const Vec2& centre, double diameter, const CircleFit& a,
                       const Vec3& e1, const Vec3& e2, const std::string& by) {
  FeatureFit f;
  f.measured = true;
  f.point = d.point + centre.x() * e1 + centre.y() * e2;
  f.diameter_mm = diameter;
  f.points = a.points;
  f.rms_mm = a.rms;
  f.measured_by = by;
  return f;
}

std::string arc_text(const std::string& seen, const CircleFit& c, int need, const Datum& d) {
  if (!c.fitted) return c.failure;
  if (std::abs(2.0 * c.circle.radius - d.diameter_mm) >
      std::max(kDiameterToleranceMm, 0.05 * d.diameter_mm))
    return "its " + seen + "'s " + (d.kind == DatumKind::kSlot ? "outline" : "circle") + " is " +
           std::to_string(2.0 * c.circle.radius) + " mm across (the " + to_string(d.kind) + " " +
           std::to_string(d.diameter_mm) + ")";
  return "its " + seen + " is seen over " + std::to_string(30 * c.sectors) + " deg only (needs " +
         std::to_string(30 * need) + ")";
}

// The feature from its wall's and its rim's fits (circles, or a slot's stadiums; centres in
// (e1, e2)): the wall where seen over min_hole_sectors, the rim on the seen skin where that is
// seen over kRimSectorsNeeded, both weighted by the information of their centres where both are
// (a wall of a one-sided view, seen over part of its outline, fixes the centre along the arc's
// middle; the rim across it).
FeatureFit by_what_is_seen(const Datum& d, const CircleFit& wall, const CircleFit& rim,
                           const DatumAlignmentSettings& s, const Vec3& e1, const Vec3& e2) {
  const auto size_ok = [&](const CircleFit& c) {
    return std::abs(2.0 * c.circle.radius - d.diameter_mm) <=
           std::max(kDiameterToleranceMm, 0.05 * d.diameter_mm);
  };
  const bool wall_whole = wall.fitted && size_ok(wall) && wall.sectors >= s.min_hole_sectors;
  const bool wall_part = wall.fitted && size_ok(wall) && wall.sectors >= kPartialWallSectors;
  const int rim_need = std::max(s.min_hole_sectors, kRimSectorsNeeded);
  const bool rim_whole = rim.fitted && size_ok(rim) && rim.sectors >= rim_need;
  if (rim_whole && wall_part) {
    const Eigen::Matrix2d info = wall.information + rim.information;
    const Vec2 c = info.ldlt().solve(wall.information * wall.circle.centre +
                                     rim.information * rim.circle.centre);
    FeatureFit f = from_circle(d, c, 2.0 * wall.circle.radius, wall, e1, e2, "wall and rim");
    f.points += rim.points;
    return f;
  }
  if (wall_whole)
    return from_circle(d, wall.circle.centre, 2.0 * wall.circle.radius, wall, e1, e2, "wall");
  if (rim_whole)
    return from_circle(d, rim.circle.centre, 2.0 * rim.circle.radius, rim, e1, e2, "rim");
  FeatureFit f;
  f.failure = wall.fitted || !wall.failure.empty() ? arc_text("wall", wall, s.min_hole_sectors, d) +
                                                         "; " + arc_text("rim", rim, rim_need, d)
                                                   : arc_text("rim", rim, rim_need, d);
  return f;
}

// The hole by what the scan shows of it (by_what_is_seen).
FeatureFit measure_hole(const Datum& d, const FeaturePoints& near, double band, double skin_band,
                        const DatumAlignmentSettings& s) {
  Vec3 e1, e2;
  complete_basis(d.normal, e1, e2);
  CircleFit wall;
  if (d.thickness_mm > 0.0) wall = robust_circle(wall_points(d, near, band, e1, e2), "wall", s);
  double spacing = 0.0;
  const double gap = rim_gap(d, near, skin_band, spacing);
  const CircleFit rim =
      robust_circle(rim_points(d, near, skin_band, gap, spacing, e1, e2), "rim", s);
  return by_what_is_seen(d, wall, rim, s, e1, e2);
}

// ---- slot: its stadium outline, from the wall where seen and the rim on the seen skin --------

// A slot's outline in its plane, in (e1, e2) = (along the slot, across it: `direction`): the
// segment of half length `half` on the axis turned by `angle` about `centre`, widened by
// `radius` (half the width). Fitted as a hole's circle is, the centre, the long axis's turn
// and the radius free (a uniform gap of the rim moves the radius only); its straight half
// length is the CAD's.
struct Stadium {
  Vec2 centre = Vec2::Zero();
  double angle = 0.0;
  double radius = 0.0;
  double half = 0.0;

  /// p in the stadium's own axes (x along its axis).
  Vec2 local(const Vec2& p) const {
    const double c = std::cos(angle), s = std::sin(angle);
    const Vec2 v = p - centre;
    return {c * v.x() + s * v.y(), -s * v.x() + c * v.y()};
  }
  /// The signed distance of q (own axes) from the outline (> 0 outside), and the outline's
  /// outward normal (own axes) at the point nearest q.
  double distance(const Vec2& q, Vec2& normal) const {
    const Vec2 v(q.x() - std::clamp(q.x(), -half, half), q.y());
    const double rho = v.norm();
    normal = rho > 1e-12 ? Vec2(v / rho) : Vec2(0.0, q.y() < 0.0 ? -1.0 : 1.0);
    return rho - radius;
  }
  double perimeter() const { return 2.0 * std::numbers::pi * radius + 4.0 * half; }
  /// Where along the outline (0 .. perimeter, counter-clockwise from (half, -radius)) the
  /// outline point nearest q (own axes) lies.
  double arc(const Vec2& q) const {
    const double pi = std::numbers::pi;
    if (q.x() > half) return (std::atan2(q.y(), q.x() - half) + 0.5 * pi) * radius;
    if (q.x() < -half) {
      double a = std::atan2(q.y(), q.x() + half);  // the left end: [pi/2, 3 pi/2]
      if (a < 0.0) a += 2.0 * pi;
      return pi * radius + 2.0 * half + (a - 0.5 * pi) * radius;
    }
    return q.y() >= 0.0 ? pi * radius + (half - q.x())
                        : 2.0 * pi * radius + 2.0 * half + (q.x() + half);
  }
};

// The normal matrix of the distances at `st` (centre x, y, angle, radius) and the right side.
Eigen::Matrix4d stadium_normal_matrix(const std::vector<Vec2>& p, const std::vector<bool>& keep,
                                      const Stadium& st, Eigen::Vector4d* b = nullptr) {
  Eigen::Matrix4d A = Eigen::Matrix4d::Zero();
  if (b) b->setZero();
  const double c = std::cos(st.angle), s = std::sin(st.angle);
  for (std::size_t i = 0; i < p.size(); ++i) {
    if (!keep[i]) continue;
    const Vec2 q = st.local(p[i]);
    Vec2 n;
    const double r = st.distance(q, n);
    // q = R(angle)^T (p - centre): d q / d centre = -R^T, d q / d angle = (q.y, -q.x).
    const Vec2 n_plane(c * n.x() - s * n.y(), s * n.x() + c * n.y());
    const Eigen::Vector4d J(-n_plane.x(), -n_plane.y(), n.x() * q.y() - n.y() * q.x(), -1.0);
    A += J * J.transpose();
    if (b) *b -= J * r;
  }
  return A;
}

std::vector<double> stadium_residuals(const std::vector<Vec2>& p, const Stadium& st) {
  std::vector<double> res(p.size());
  Vec2 n;
  for (std::size_t i = 0; i < p.size(); ++i) res[i] = st.distance(st.local(p[i]), n);
  return res;
}

// A robust stadium (Gauss-Newton from the nominal, outliers beyond outlier_sigmas left out) and
// what it is worth, as robust_circle: its centre's information, the twelfths of its outline
// covered (`sectors`).
CircleFit robust_stadium(const std::vector<Vec2>& pts, Stadium st, const std::string& seen,
                         const DatumAlignmentSettings& s) {
  CircleFit out;
  if (pts.size() < s.min_points) {
    out.failure = too_few(pts.size(), "on the slot's " + seen, s.min_points).failure;
    return out;
  }
  std::vector<bool> keep(pts.size(), true);
  std::vector<double> res;
  for (int round = 0; round < kRobustRounds; ++round) {
    for (int it = 0; it < 20; ++it) {
      Eigen::Vector4d b;
      const Eigen::Matrix4d A = stadium_normal_matrix(pts, keep, st, &b);
      const Eigen::Vector4d step = A.ldlt().solve(b);
      if (!step.allFinite()) break;
      st.centre += step.head<2>();
      st.angle += step(2);
      st.radius += step(3);
      if (step.norm() < 1e-10) break;
    }
    res = stadium_residuals(pts, st);
    const auto next = inliers_of(res, s.outlier_sigmas);
    if (next == keep) break;
    keep = next;
  }
  out.rms = rms_of(res, keep, out.points);
  out.circle.centre = st.centre;
  out.circle.radius = st.radius;
  if (out.points < s.min_points) {
    out.failure = too_few(out.points, "on the slot's " + seen + " outline", s.min_points).failure;
    return out;
  }
  std::array<bool, 12> seen_part{};
  const double perimeter = st.perimeter();
  for (std::size_t i = 0; i < pts.size(); ++i)
    if (keep[i])
      seen_part[std::min<std::size_t>(
          11, static_cast<std::size_t>(12.0 * st.arc(st.local(pts[i])) / perimeter))] = true;
  out.sectors = static_cast<int>(std::count(seen_part.begin(), seen_part.end(), true));
  const Eigen::Matrix4d cov =
      stadium_normal_matrix(pts, keep, st).inverse() * std::max(out.rms * out.rms, 1e-6);
  out.information = cov.topLeftCorner<2, 2>().inverse();
  out.fitted = out.information.allFinite() && std::isfinite(st.radius);
  return out;
}

// The slot's nominal outline in (along, direction).
Stadium nominal_stadium(const Datum& d) {
  Stadium st;
  st.radius = 0.5 * d.diameter_mm;
  st.half = 0.5 * (d.length_mm - d.diameter_mm);
  return st;
}

// Wall points of a slot: between the two skins (clear of their rims), within `band` of its
// outline. In (e1, e2) = (along, direction).
std::vector<Vec2> slot_wall_points(const Datum& d, const FeaturePoints& near, double band,
                                   const Vec3& e1, const Vec3& e2) {
  const Stadium st = nominal_stadium(d);
  std::vector<Vec2> pts;
  Vec2 n;
  for (std::size_t i = 0; i < near.points.size(); ++i) {
    const Vec3 v = near.points[i] - d.point;
    const double h = v.dot(d.normal);
    if (h > -kSkinMarginMm || h < -d.thickness_mm + kSkinMarginMm) continue;
    const Vec2 uv(v.dot(e1), v.dot(e2));
    if (std::abs(st.distance(uv, n)) > band || !on_wall(near, i, d.normal)) continue;
    pts.push_back(uv);
  }
  return pts;
}

// The rim of a slot all round its outline, as a hole's (rim_points): per stretch of the outline
// (the arc of a hole's sector at the slot's radius) the innermost skin point within band of it,
// moved in along the outline's normal by the mean gap (measured at the outline kGapLineMm
// outside, in stretches of the same length).
std::vector<Vec2> slot_rim_points(const Datum& d, const FeaturePoints& near, double band,
                                  double gap, double spacing, const Vec3& e1, const Vec3& e2) {
  const Stadium st = nominal_stadium(d);
  Stadium line = st;
  line.radius += kGapLineMm;
  const double arc = 2.0 * std::numbers::pi / kRimSectors * st.radius;
  const auto stretches = static_cast<std::size_t>(std::max(1.0, std::round(st.perimeter() / arc)));
  const auto line_stretches = static_cast<std::size_t>(line.perimeter() / arc);
  const double reach = std::min(gap, kRimReachMm - kGapLineMm);
  std::vector<double> inner(stretches, kNone);
  std::vector<Vec2> rim(stretches, Vec2::Zero()), normal(stretches, Vec2::Zero());
  std::vector<GapSample> samples;
  const double skin =
      near.normals.empty() && d.thickness_mm > 0.0 ? std::min(band, kSkinMarginMm) : band;
  Vec2 n;
  for (std::size_t i = 0; i < near.points.size(); ++i) {
    const Vec3 v = near.points[i] - d.point;
    if (std::abs(v.dot(d.normal)) > skin || !facing(near, i, d.normal, kSkinNormal)) continue;
    const Vec2 uv(v.dot(e1), v.dot(e2));
    const double beyond = st.distance(uv, n);
    if (beyond < -band) continue;
    if (beyond >= 0.5 * kGapLineMm && beyond <= kGapLineMm + reach && line_stretches > 0)
      samples.push_back(
          {beyond, std::min(line_stretches - 1, static_cast<std::size_t>(line.arc(uv) / arc))});
    if (beyond > band + gap) continue;
    const auto k =
        std::min(stretches - 1, static_cast<std::size_t>(st.arc(uv) / st.perimeter() * stretches));
    if (beyond < inner[k]) inner[k] = beyond, rim[k] = uv, normal[k] = n;
  }
  const double mean_gap = skin_gap(samples, line_stretches, reach, rim_gap_mean(spacing, arc));
  std::vector<Vec2> pts;
  for (std::size_t k = 0; k < stretches; ++k)
    if (inner[k] != kNone) pts.push_back(rim[k] - mean_gap * normal[k]);
  return pts;
}

// The slot by what the scan shows of its outline (by_what_is_seen), its centre in the plane;
// the datum fixes the direction across it only.
FeatureFit measure_slot(const Datum& d, const FeaturePoints& near, double band, double skin_band,
                        const DatumAlignmentSettings& s, bool walls_too = true) {
  const Vec3 e1 = d.normal.cross(d.direction), e2 = d.direction;
  CircleFit wall;
  if (walls_too && d.thickness_mm > 0.0)
    wall = robust_stadium(slot_wall_points(d, near, band, e1, e2), nominal_stadium(d), "wall", s);
  double spacing = 0.0;
  const double gap = rim_gap(d, near, skin_band, spacing);
  const CircleFit rim = robust_stadium(slot_rim_points(d, near, skin_band, gap, spacing, e1, e2),
                                       nominal_stadium(d), "rim", s);
  return by_what_is_seen(d, wall, rim, s, e1, e2);
}

// ---- edge: the band estimate of the skin's end -----------------------------------------------

// The edge's end face (the sheet's cut, between its skins, facing out across the edge): the
// robust mean of its points' positions across the edge, or nothing when fewer than min_points
// are seen. A laser looking across the edge sees it as it sees a hole's wall.
std::optional<FeatureFit> edge_face(const Datum& d, const FeaturePoints& near, double band,
                                    const DatumAlignmentSettings& s) {
  if (d.thickness_mm <= 0.0) return std::nullopt;
  const Vec3 along = d.normal.cross(d.direction);
  std::vector<double> u;
  for (std::size_t i = 0; i < near.points.size(); ++i) {
    const Vec3 v = near.points[i] - d.point;
    const double h = v.dot(d.normal), across = v.dot(d.direction);
    if (h > -kSkinMarginMm || h < -d.thickness_mm + kSkinMarginMm) continue;
    if (std::abs(across) > band || std::abs(v.dot(along)) > d.radius_mm) continue;
    if (facing(near, i, d.direction, kSkinNormal)) u.push_back(across);
  }
  if (u.size() < s.min_points) return std::nullopt;
  std::vector<double> sorted = u;
  const auto mid = sorted.begin() + static_cast<long>(sorted.size() / 2);
  std::nth_element(sorted.begin(), mid, sorted.end());
  double centre = *mid;
  std::vector<double> res(u.size());
  std::vector<bool> keep(u.size(), true);
  for (int round = 0; round < kRobustRounds; ++round) {
    for (std::size_t i = 0; i < u.size(); ++i) res[i] = u[i] - centre;
    keep = inliers_of(res, s.outlier_sigmas);
    double sum = 0.0;
    std::size_t n = 0;
    for (std::size_t i = 0; i < u.size(); ++i)
      if (keep[i]) sum += u[i], ++n;
    if (n < s.min_points) return std::nullopt;
    centre = sum / static_cast<double>(n);
  }
  for (std::size_t i = 0; i < u.size(); ++i) res[i] = u[i] - centre;
  FeatureFit f;
  f.measured = true;
  f.measured_by = "end face";
  f.point = d.point + centre * d.direction;
  f.rms_mm = rms_of(res, keep, f.points);
  return f;
}

// An edge by its end face where seen (sharp, as a wall), else by the band estimate of the
// skin's end (boundary.hpp).
FeatureFit measure_edge(const Datum& d, const FeaturePoints& near, double band, double skin_band,
                        const DatumAlignmentSettings& s) {
  if (auto face = edge_face(d, near, band, s)) return *face;
  const Vec3 along = d.normal.cross(d.direction);
  std::vector<double> u;
  for (std::size_t i = 0; i < near.points.size(); ++i) {
    const Vec3 v = near.points[i] - d.point;
    const double h = v.dot(d.normal), a = v.dot(along), across = v.dot(d.direction);
    if (std::abs(h) > skin_band || std::abs(a) > d.radius_mm) continue;
    if (across < -(skin_band + 2.0 * kEdgeBandMm) || !facing(near, i, d.normal, kSkinNormal))
      continue;
    u.push_back(across);
  }
  const auto end = high_end(u, kEdgeBandMm, s.min_points, kEdgeSkip);
  if (!end) return too_few(u.size(), "on the skin at the edge", s.min_points + kEdgeSkip);
  FeatureFit f;
  f.measured = true;
  f.measured_by = "skin's end";
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
      return std::hypot(0.5 * d.diameter_mm + band_mm + kRimReachMm, wall);
    case DatumKind::kSlot:
      return std::hypot(0.5 * d.length_mm + band_mm + kRimReachMm, wall);
    case DatumKind::kEdge:
      return std::hypot(d.radius_mm, band_mm + 2.0 * kEdgeBandMm, band_mm + d.thickness_mm);
  }
  return 0.0;
}

FeatureFit measure_feature(const Datum& d, const FeaturePoints& near, double band_mm,
                           const DatumAlignmentSettings& s) {
  const double skin_band = skin_band_of(d, band_mm);
  switch (d.kind) {
    case DatumKind::kPad:
      return measure_pad(d, near, skin_band, s);
    case DatumKind::kHole:
      return measure_hole(d, near, band_mm, skin_band, s);
    case DatumKind::kSlot:
      return measure_slot(d, near, band_mm, skin_band, s);
    case DatumKind::kEdge:
      return measure_edge(d, near, band_mm, skin_band, s);
  }
  return {};
}

FeatureFit measure_rim(const Datum& d, const FeaturePoints& near, double band_mm,
                       const DatumAlignmentSettings& s) {
  const double skin_band = skin_band_of(d, band_mm);
  if (d.kind == DatumKind::kSlot) return measure_slot(d, near, band_mm, skin_band, s, false);
  Vec3 e1, e2;
  complete_basis(d.normal, e1, e2);
  double spacing = 0.0;
  const double gap = rim_gap(d, near, skin_band, spacing);
  const CircleFit rim =
      robust_circle(rim_points(d, near, skin_band, gap, spacing, e1, e2), "rim", s);
  const int rim_need = std::max(s.min_hole_sectors, kRimSectorsNeeded);
  if (!rim.fitted || rim.sectors < rim_need ||
      std::abs(2.0 * rim.circle.radius - d.diameter_mm) >
          std::max(kDiameterToleranceMm, 0.05 * d.diameter_mm)) {
    FeatureFit f;
    f.failure = arc_text("rim", rim, rim_need, d);
    return f;
  }
  return from_circle(d, rim.circle.centre, 2.0 * rim.circle.radius, rim, e1, e2, "rim");
}

double skin_spacing(const Datum& d, const FeaturePoints& near, double band_mm, double r_in,
                    double r_out) {
  std::size_t n = 0;
  for (std::size_t i = 0; i < near.points.size(); ++i) {
    const Vec3 v = near.points[i] - d.point;
    const double h = v.dot(d.normal);
    const double rho = (v - h * d.normal).norm();
    if (std::abs(h) <= band_mm && rho >= r_in && rho <= r_out &&
        facing(near, i, d.normal, kSkinNormal))
      ++n;
  }
  if (n == 0) return 0.0;
  const double area = std::numbers::pi * (r_out * r_out - r_in * r_in);
  return std::sqrt(area / static_cast<double>(n));
}

}  // namespace springscan::analysis::datum_detail
