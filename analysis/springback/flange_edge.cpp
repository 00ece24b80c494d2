#include "analysis/springback/flange_edge.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace springscan::analysis {
namespace {

// The height of the fitted surface at (s, t): h = A (s^2 + h^2) + (B + G t) s + C + E t,
// solved by fixed-point steps (A h^2 is tiny next to h on a flange).
double surface_h(const FlangeSurface& f, double s, double t) {
  const double base = f.A * s * s + (f.B + f.G * t) * s + f.C + f.E * t;
  double h = base;
  for (int i = 0; i < 4; ++i) h = base + f.A * h * h;
  return h;
}

// The flange's model samples in its frame, as (t, s towards the edge), and their extent along
// the edge.
struct Samples {
  std::vector<Eigen::Vector2d> ts;
  double t_min = std::numeric_limits<double>::infinity();
  double t_max = -std::numeric_limits<double>::infinity();
};

Samples flange_samples(const PartModel& model, const Flange& flange, const FlangeFrame& frame,
                       double out) {
  Samples e;
  const PointCloud& s = model.samples;
  std::vector<Vec3> q;
  for (std::size_t i = 0; i < s.size(); ++i)
    if (std::find(flange.face_ids.begin(), flange.face_ids.end(), s.face_ids[i]) !=
        flange.face_ids.end())
      q.push_back(frame.local(s.points[i]));
  // A solid's flange has both sides of the sheet; the scanned side is the one nearer the scan's
  // points (h = 0 at their centroid). Its outline is the edge: the other side's may differ (a
  // chamfer, a draft).
  double h_lo = std::numeric_limits<double>::infinity(), h_hi = -h_lo;
  for (const Vec3& p : q) h_lo = std::min(h_lo, p.z()), h_hi = std::max(h_hi, p.z());
  const double mid = 0.5 * (h_lo + h_hi);
  const bool two_sides = h_hi - h_lo > 0.5 * flange.thickness_mm && flange.thickness_mm > 0.0;
  const bool upper = std::abs(h_hi) < std::abs(h_lo);
  for (const Vec3& p : q) {
    if (two_sides && (p.z() > mid) != upper) continue;
    e.ts.emplace_back(p.y(), out * p.x());
    e.t_min = std::min(e.t_min, p.y());
    e.t_max = std::max(e.t_max, p.y());
  }
  return e;
}

struct Strip {
  double cad_s = 0.0, cad_h = 0.0;  // the CAD edge at the strip's centre (s times `out`)
  double centre = 0.0;
  std::size_t count = 0;  // scan points in the band
};

// The edge as a line s = a + b t: of the lines above every point (t, s), the one with the least
// area under it over the points' span, which passes through the edge of their upper convex hull
// above the span's middle (the maximum-likelihood edge of points uniform below a straight edge).
// One far point per strip would give each strip's edge alone, with the exponential tail of the
// largest of a few hundred uniform values (a strip 0.07 mm short in 1 of 300); the line uses
// every strip's points at once.
Eigen::Vector2d upper_hull_line(std::vector<Eigen::Vector2d> p) {
  std::sort(p.begin(), p.end(), [](const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
    return a.x() < b.x() || (a.x() == b.x() && a.y() < b.y());
  });
  std::vector<Eigen::Vector2d> hull;
  for (const Eigen::Vector2d& q : p) {
    // Keep turning clockwise (the upper hull, left to right).
    while (hull.size() >= 2) {
      const Eigen::Vector2d a = hull[hull.size() - 2], b = hull.back();
      if ((b - a).x() * (q - a).y() - (b - a).y() * (q - a).x() >= 0.0)
        hull.pop_back();
      else
        break;
    }
    hull.push_back(q);
  }
  if (hull.size() < 2) return {hull.empty() ? 0.0 : hull[0].y(), 0.0};
  const double middle = 0.5 * (p.front().x() + p.back().x());
  std::size_t i = 1;
  while (i + 1 < hull.size() && hull[i].x() < middle) ++i;
  const Eigen::Vector2d a = hull[i - 1], b = hull[i];
  const double slope = (b.y() - a.y()) / std::max(b.x() - a.x(), 1e-12);
  return {a.y() - slope * a.x(), slope};
}

}  // namespace

EdgeDeviation measure_free_edge(const PartModel& model, const Flange& flange,
                                const FlangeShape& shape, const Vec3& bend_axis_point,
                                const PointCloud& scan, std::span<const std::uint32_t> points,
                                const FlangeEdgeSettings& st) {
  EdgeDeviation result;
  if (!shape.measured || !model.distance || !model.samples.has_face_ids()) return result;
  const FlangeFrame& frame = shape.frame;
  // The free edge lies on the side of the centroid away from the bend.
  const double out = frame.local(bend_axis_point).x() < 0.0 ? 1.0 : -1.0;
  const Samples samples = flange_samples(model, flange, frame, out);
  const double length = samples.t_max - samples.t_min;
  if (!(length > 0.0) || !(st.strip_length_mm > 0.0)) return result;
  const auto n = static_cast<std::size_t>(
      std::max<long>(st.min_strips, std::lround(length / st.strip_length_mm)));
  const double window = length / static_cast<double>(n);
  const auto strip_of = [&](double t) { return std::floor((t - samples.t_min) / window); };
  std::vector<Strip> strips(n);
  std::vector<double> outermost(n, -std::numeric_limits<double>::infinity());
  for (const Eigen::Vector2d& p : samples.ts) {
    const double k = std::min(strip_of(p.x()), static_cast<double>(n - 1));
    outermost[static_cast<std::size_t>(k)] =
        std::max(outermost[static_cast<std::size_t>(k)], p.y());
  }
  // The CAD edge at each strip's centre: the closest surface point to a point in the plane 1 mm
  // beyond the strip's outermost sample lies on the edge there.
  Eigen::Matrix2d normal = Eigen::Matrix2d::Zero();
  Eigen::Vector2d rhs = Eigen::Vector2d::Zero();
  for (std::size_t k = 0; k < n; ++k) {
    Strip& strip = strips[k];
    strip.centre = samples.t_min + (static_cast<double>(k) + 0.5) * window;
    const double beyond = out * (outermost[k] + 1.0);
    const Vec3 query = frame.origin + beyond * frame.u + strip.centre * frame.d;
    const Vec3 foot = frame.local(model.distance->closest(query).foot);
    strip.cad_s = out * foot.x();
    strip.cad_h = foot.z();
    const Eigen::Vector2d x(1.0, strip.centre);
    normal += x * x.transpose();
    rhs += x * strip.cad_s;
  }
  // Only a straight CAD edge is measured: the scan's edge is taken as a straight line. A tab,
  // a notch or a curved outline is left out rather than reported against the wrong line.
  const Eigen::Vector2d cad_line = normal.ldlt().solve(rhs);
  for (const Strip& strip : strips)
    if (!(std::abs(strip.cad_s - cad_line[0] - cad_line[1] * strip.centre) <= st.max_edge_bend_mm))
      return result;
  // The scan points within the band inside the CAD edge, as (t, s towards the edge).
  std::vector<Eigen::Vector2d> band;
  const auto add = [&](const Vec3& q) {
    const double k = strip_of(q.y());
    if (!(k >= 0.0 && k < static_cast<double>(n))) return;
    Strip& strip = strips[static_cast<std::size_t>(k)];
    const double s = out * q.x();
    if (s < strip.cad_s - st.band_mm || s > strip.cad_s + st.band_mm) return;
    band.emplace_back(q.y(), s);
    ++strip.count;
  };
  for (std::uint32_t i : points) {
    const Vec3 q = frame.local(scan.points[i]);
    if (std::abs(q.z() - surface_h(shape.surface, q.x(), q.y())) <= shape.inlier_threshold_mm)
      add(q);
  }
  if (band.size() < 2) return result;
  // The line of the hull lies below the edge by about one point's share of the band's area
  // spread over its length: band_mm / n.
  Eigen::Vector2d line = upper_hull_line(band);
  line[0] += st.band_mm / static_cast<double>(band.size());
  double in_sum = 0.0, across_sum = 0.0;
  result.in_plane_min_mm = result.across_min_mm = std::numeric_limits<double>::infinity();
  result.in_plane_max_mm = result.across_max_mm = -std::numeric_limits<double>::infinity();
  for (const Strip& strip : strips) {
    if (strip.count < static_cast<std::size_t>(std::max(st.min_points_per_strip, 2))) continue;
    const double edge = line[0] + line[1] * strip.centre;
    const double in_plane = edge - strip.cad_s;
    const double across = surface_h(shape.surface, out * edge, strip.centre) - strip.cad_h;
    in_sum += in_plane;
    across_sum += across;
    result.in_plane_min_mm = std::min(result.in_plane_min_mm, in_plane);
    result.in_plane_max_mm = std::max(result.in_plane_max_mm, in_plane);
    result.across_min_mm = std::min(result.across_min_mm, across);
    result.across_max_mm = std::max(result.across_max_mm, across);
    const auto point = [&](double s, double h) {
      return Vec3(frame.origin + out * s * frame.u + strip.centre * frame.d + h * frame.n);
    };
    result.cad_edge.push_back(point(strip.cad_s, strip.cad_h));
    result.scan_edge.push_back(point(edge, strip.cad_h + across));
    ++result.strips;
  }
  // Every strip must see the edge: a strip the scan does not reach (occlusion, a missing area)
  // would leave the straight line to the others' points and report an edge nobody saw.
  if (result.strips < static_cast<int>(n)) return EdgeDeviation{};
  result.in_plane_mean_mm = in_sum / result.strips;
  result.across_mean_mm = across_sum / result.strips;
  result.measured = true;
  return result;
}

}  // namespace springscan::analysis
