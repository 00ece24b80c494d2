// The capture round of the datum alignment (datum.hpp step 1): each datum's feature found where
// the best fit may have left it, up to capture_mm off its nominal and tilted a few degrees. The
// narrow measurements (datum_measure.cpp) look within a millimetre; springback elsewhere on the
// part pulls the best fit farther than that at the datums (issue 40: 0.3-3.2 mm, 1.9 deg).
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <numbers>

#include "analysis/registration/boundary.hpp"
#include "analysis/registration/datum_internal.hpp"

namespace springscan::analysis::datum_detail {
namespace {

constexpr double kBinMm = 0.1;         // the height histogram's bins
constexpr double kNearlyFull = 0.5;    // a height window this full of the fullest: a skin
constexpr double kRingMm = 3.0;        // the skin's plane is taken this far around an outline
constexpr double kSkinNormal = 0.8;    // n . normal above this: a point of the datum's skin
constexpr double kPlaneBandMm = 0.3;   // skin points this close to the found plane
constexpr double kEdgeBandMm = 1.0;    // the band that locates an edge (boundary.hpp step 1)
constexpr std::size_t kEdgeSkip = 2;   // stray points beyond the edge
constexpr double kMinRingShare = 0.8;  // an outline's ring at least this full of skin
constexpr double kCellSpacings = 2.0;
constexpr double kStrayShare = 0.02;     // of an outline's inside cells: stray points  // occupancy
                                         // cells this many point spacings wide
constexpr double kCaptureTiltDeg = 3.0;  // the tilt the height window allows for

struct Plane {
  bool found = false;
  Vec3 point = Vec3::Zero(), normal = Vec3::UnitZ();
  std::size_t points = 0;
};

bool facing(const FeaturePoints& near, std::size_t i, const Vec3& n) {
  return near.normals.empty() || near.normals[i].dot(n) > kSkinNormal;
}

double skin_band(const Datum& d) {
  return d.thickness_mm > 0.0 ? std::min(kPlaneBandMm, 0.45 * d.thickness_mm) : kPlaneBandMm;
}

// The plane of `pts` (least squares), its normal on the side of `n`.
Plane fit_plane(const std::vector<Vec3>& pts, const Vec3& n) {
  Plane p;
  if (pts.size() < 3) return p;
  for (const Vec3& q : pts) p.point += q;
  p.point /= static_cast<double>(pts.size());
  Mat3 cov = Mat3::Zero();
  for (const Vec3& q : pts) cov += (q - p.point) * (q - p.point).transpose();
  p.normal = Eigen::SelfAdjointEigenSolver<Mat3>(cov).eigenvectors().col(0);
  if (p.normal.dot(n) < 0.0) p.normal = -p.normal;
  p.points = pts.size();
  p.found = true;
  return p;
}

// The dominant skin facing the datum's normal among the points whose distance from its normal
// line lies in [r_in, r_out] and whose height along it lies within +-capture: the fullest window
// of heights (wide enough for the tilt over r_out), the one nearest the nominal among those
// nearly as full (a points-only scan of both skins); then the plane of the points in that
// window, and again of the points within the skin band of that plane.
Plane dominant_plane(const Datum& d, const FeaturePoints& near, double r_in, double r_out,
                     double capture, std::size_t min_points) {
  const int bins = static_cast<int>(std::ceil(2.0 * capture / kBinMm)) + 1;
  std::vector<int> count(static_cast<std::size_t>(bins), 0);
  std::vector<Vec3> pts;
  std::vector<double> heights;
  for (std::size_t i = 0; i < near.points.size(); ++i) {
    const Vec3 v = near.points[i] - d.point;
    const double h = v.dot(d.normal), rho = (v - h * d.normal).norm();
    if (std::abs(h) > capture || rho < r_in || rho > r_out || !facing(near, i, d.normal)) continue;
    pts.push_back(near.points[i]);
    heights.push_back(h);
    ++count[static_cast<std::size_t>((h + capture) / kBinMm)];
  }
  const double window =
      2.0 * r_out * std::tan(kCaptureTiltDeg * std::numbers::pi / 180.0) + 2.0 * kPlaneBandMm;
  const int w = std::max(1, static_cast<int>(std::ceil(window / kBinMm)));
  std::vector<int> sum(static_cast<std::size_t>(bins), 0);
  int fullest = 0;
  for (int b = 0; b < bins; ++b) {
    for (int k = b; k < std::min(bins, b + w); ++k)
      sum[static_cast<std::size_t>(b)] += count[static_cast<std::size_t>(k)];
    fullest = std::max(fullest, sum[static_cast<std::size_t>(b)]);
  }
  if (fullest < static_cast<int>(min_points)) return {};
  double best_h = 0.0, best_off = std::numeric_limits<double>::infinity();
  for (int b = 0; b < bins; ++b) {
    if (sum[static_cast<std::size_t>(b)] < kNearlyFull * fullest) continue;
    const double mid = -capture + (b + 0.5 * w) * kBinMm;
    if (std::abs(mid) < best_off) best_off = std::abs(mid), best_h = mid;
  }
  std::vector<Vec3> in;
  for (std::size_t i = 0; i < pts.size(); ++i)
    if (std::abs(heights[i] - best_h) <= 0.5 * window) in.push_back(pts[i]);
  Plane p = fit_plane(in, d.normal);
  for (int round = 0; round < 2 && p.found; ++round) {
    in.clear();
    for (const Vec3& q : pts)
      if (std::abs((q - p.point).dot(p.normal)) <= skin_band(d)) in.push_back(q);
    p = fit_plane(in, d.normal);
  }
  if (p.points < min_points) return {};
  return p;
}

// The datum moved onto the plane (its point's foot there, its normal the plane's).
Datum on_plane(const Datum& d, const Plane& p) {
  Datum out = d;
  out.point = d.point - (d.point - p.point).dot(p.normal) * p.normal;
  out.normal = p.normal;
  if (!d.direction.isZero())
    out.direction = (d.direction - d.direction.dot(p.normal) * p.normal).normalized();
  return out;
}

FeatureFit not_found(const std::string& why, bool contradicted = false) {
  FeatureFit f;
  f.failure = why;
  f.contradicted = contradicted;
  return f;
}

// At least min_points scan points within [r_in, r_out] of the datum's normal line and within
// +-capture along it that face away from its normal: the scan sees another skin there.
bool skin_facing_away(const Datum& d, const FeaturePoints& near, double r_in, double r_out,
                      double capture, std::size_t min_points) {
  if (near.normals.empty()) return false;
  std::size_t n = 0;
  for (std::size_t i = 0; i < near.points.size(); ++i) {
    const Vec3 v = near.points[i] - d.point;
    const double h = v.dot(d.normal), rho = (v - h * d.normal).norm();
    if (std::abs(h) <= capture && rho >= r_in && rho <= r_out && near.normals[i].dot(d.normal) < 0)
      ++n;
  }
  return n >= min_points;
}

FeatureFit capture_pad(const Datum& d, const FeaturePoints& near, double capture,
                       const DatumAlignmentSettings& s) {
  const Plane p = dominant_plane(d, near, 0.0, d.radius_mm, capture, s.min_points);
  if (!p.found)
    return not_found("no skin facing the pad within " + std::to_string(capture) + " mm",
                     skin_facing_away(d, near, 0.0, d.radius_mm, capture, s.min_points));
  // Where the found plane crosses the pad's normal line: what the pad fixes.
  FeatureFit f;
  f.measured = true;
  f.point = d.point + (p.normal.dot(p.point - d.point) / p.normal.dot(d.normal)) * d.normal;
  f.normal = p.normal;
  f.points = p.points;
  f.measured_by = "plane";
  return f;
}

// Signed distance of the in-plane offset (x along e1, y along e2) from the outline of a hole
// (radius r) or a slot (half width r, straight half length `half` along `along`): < 0 inside.
double outline_distance(const Eigen::Vector2d& p, double r, double half,
                        const Eigen::Vector2d& along) {
  const double t = std::clamp(p.dot(along), -half, half);
  return (p - t * along).norm() - r;
}

// A hole or slot: where its outline, shrunk by a cell, holds the fewest occupied cells of the
// skin's occupancy grid, and its ring outside the most (an empty region that is not the hole,
// such as the part's outside, has no skin around it); the mean of the positions that tie; then
// its rim about that centre.
FeatureFit capture_outline(const Datum& d, const FeaturePoints& near, double capture,
                           const DatumAlignmentSettings& s) {
  const bool slot = d.kind == DatumKind::kSlot;
  const double r = 0.5 * d.diameter_mm;
  const double half = slot ? 0.5 * (d.length_mm - d.diameter_mm) : 0.0;
  const double reach = r + half;
  const Plane p = dominant_plane(d, near, reach, reach + capture + kRingMm, capture, s.min_points);
  if (!p.found)
    return not_found(
        "no skin around it within " + std::to_string(capture) + " mm",
        skin_facing_away(d, near, reach, reach + capture + kRingMm, capture, s.min_points));
  const Datum dp = on_plane(d, p);
  Vec3 e1, e2;
  complete_basis(dp.normal, e1, e2);
  const Vec3 along3 = slot ? Vec3(dp.normal.cross(dp.direction)) : e1;
  const Eigen::Vector2d along(along3.dot(e1), along3.dot(e2));
  std::vector<Eigen::Vector2d> skin;
  for (std::size_t i = 0; i < near.points.size(); ++i) {
    const Vec3 v = near.points[i] - dp.point;
    if (std::abs(v.dot(dp.normal)) <= skin_band(d) && facing(near, i, dp.normal))
      skin.emplace_back(v.dot(e1), v.dot(e2));
  }
  const double outer = reach + capture + kRingMm;
  const double area = std::numbers::pi * (outer * outer - reach * reach);
  const double spacing = std::sqrt(area / std::max<double>(1.0, static_cast<double>(skin.size())));
  // About four points per cell: a cell of the skin is rarely empty (2 %).
  const double cell = std::clamp(kCellSpacings * spacing, 0.2, 2.5);
  const int n = static_cast<int>(std::ceil(outer / cell));
  const int side = 2 * n + 1;
  std::vector<char> occupied(static_cast<std::size_t>(side * side), 0);
  const auto index = [&](int x, int y) { return static_cast<std::size_t>((y + n) * side + x + n); };
  for (const Eigen::Vector2d& q : skin) {
    const int x = static_cast<int>(std::lround(q.x() / cell)),
              y = static_cast<int>(std::lround(q.y() / cell));
    if (std::abs(x) <= n && std::abs(y) <= n) occupied[index(x, y)] = 1;
  }
  const double ring = std::max(1.0, 2.0 * cell);
  std::vector<std::pair<int, int>> inside, around;
  const int m = static_cast<int>(std::ceil((reach + cell + ring) / cell));
  for (int y = -m; y <= m; ++y)
    for (int x = -m; x <= m; ++x) {
      const double sd = outline_distance(Eigen::Vector2d(x, y) * cell, r, half, along);
      if (sd <= -cell) inside.emplace_back(x, y);
      if (sd >= cell && sd <= cell + ring) around.emplace_back(x, y);
    }
  const int c = static_cast<int>(std::ceil(capture / cell));
  struct Score {
    int x, y, inside;
    double ring;
  };
  std::vector<Score> scores;
  int least = std::numeric_limits<int>::max();
  for (int y = -c; y <= c; ++y)
    for (int x = -c; x <= c; ++x) {
      if (std::hypot(x, y) * cell > capture) continue;
      const auto at = [&](const std::pair<int, int>& o) {
        const int u = x + o.first, v = y + o.second;
        return std::abs(u) <= n && std::abs(v) <= n && occupied[index(u, v)];
      };
      const int in = static_cast<int>(std::count_if(inside.begin(), inside.end(), at));
      const double full = static_cast<double>(std::count_if(around.begin(), around.end(), at)) /
                          static_cast<double>(std::max<std::size_t>(1, around.size()));
      scores.push_back({x, y, in, full});
      least = std::min(least, in);
    }
  double best_ring = 0.0;
  for (const Score& k : scores)
    if (k.inside == least) best_ring = std::max(best_ring, k.ring);
  // The outline's inside empty of skin but for stray points (outliers, noise at its rim).
  const int stray = std::max(2, static_cast<int>(kStrayShare * static_cast<double>(inside.size())));
  if (least > stray)
    return not_found("no empty outline of it in the seen skin within " + std::to_string(capture) +
                         " mm (" + std::to_string(least) + " cells of skin inside at best)",
                     true);
  if (best_ring < kMinRingShare)
    return not_found("no outline of it in the seen skin within " + std::to_string(capture) +
                     " mm (its ring " + std::to_string(static_cast<int>(100 * best_ring)) +
                     " % skin)");
  Eigen::Vector2d centre = Eigen::Vector2d::Zero();
  int tied = 0;
  for (const Score& k : scores)
    if (k.inside == least && k.ring >= best_ring - 0.05)
      centre += Eigen::Vector2d(k.x, k.y), ++tied;
  centre *= cell / tied;
  // Refined on the rim about that centre (datum_measure.cpp), else the grid's centre: a small
  // hole in a sparse (strided) scan, its band a cell and more wide, gives no rim of its size
  // (a 4.3 mm hole's came out 5.3-6 mm across on the openamr side panel), and the grid's
  // centre is within a cell of it, which the search round's band reaches.
  Datum found = dp;
  found.point = dp.point + centre.x() * e1 + centre.y() * e2;
  FeatureFit f = measure_rim(found, near, 1.5 * cell + kPlaneBandMm, s);
  if (f.measured) return f;
  f = FeatureFit{};
  f.measured = true;
  f.point = found.point;
  f.diameter_mm = d.diameter_mm;
  f.points = skin.size();
  f.rms_mm = cell;
  f.measured_by = "outline";
  return f;
}

FeatureFit capture_edge(const Datum& d, const FeaturePoints& near, double capture,
                        const DatumAlignmentSettings& s) {
  const Plane p = dominant_plane(d, near, 0.0, d.radius_mm + capture, capture, s.min_points);
  if (!p.found) return not_found("no skin at the edge within " + std::to_string(capture) + " mm");
  const Datum dp = on_plane(d, p);
  const Vec3 along = dp.normal.cross(dp.direction);
  std::vector<double> u;
  for (std::size_t i = 0; i < near.points.size(); ++i) {
    const Vec3 v = near.points[i] - dp.point;
    if (std::abs(v.dot(dp.normal)) > skin_band(d) || std::abs(v.dot(along)) > d.radius_mm ||
        !facing(near, i, dp.normal))
      continue;
    u.push_back(v.dot(dp.direction));
  }
  const auto end = high_end(u, kEdgeBandMm, s.min_points, kEdgeSkip);
  if (!end) return not_found("too few scan points on the skin at the edge");
  FeatureFit f;
  f.measured = true;
  f.point = dp.point + *end * dp.direction;
  f.points = u.size();
  f.measured_by = "skin's end";
  return f;
}

}  // namespace

double capture_radius(const Datum& d, double capture_mm) {
  const double wall = d.thickness_mm + capture_mm;
  switch (d.kind) {
    case DatumKind::kPad:
      return std::hypot(d.radius_mm, capture_mm);
    case DatumKind::kHole:
      return std::hypot(0.5 * d.diameter_mm + capture_mm + kRingMm, wall);
    case DatumKind::kSlot:
      return std::hypot(0.5 * d.length_mm + capture_mm + kRingMm, wall);
    case DatumKind::kEdge:
      return std::hypot(d.radius_mm + capture_mm, capture_mm + 2.0 * kEdgeBandMm, capture_mm);
  }
  return 0.0;
}

FeatureFit capture_feature(const Datum& d, const FeaturePoints& near, double capture_mm,
                           const DatumAlignmentSettings& s) {
  switch (d.kind) {
    case DatumKind::kPad:
      return capture_pad(d, near, capture_mm, s);
    case DatumKind::kHole:
    case DatumKind::kSlot:
      return capture_outline(d, near, capture_mm, s);
    case DatumKind::kEdge:
      return capture_edge(d, near, capture_mm, s);
  }
  return {};
}

}  // namespace springscan::analysis::datum_detail
