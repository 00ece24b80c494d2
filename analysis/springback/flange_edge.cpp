#include "analysis/springback/flange_edge.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <optional>
#include <vector>

namespace springscan::analysis {
namespace {

using Vec2 = Eigen::Vector2d;

// The height of the fitted surface at (s, t): h = A (s^2 + h^2) + (B + G t) s + C + E t,
// solved by fixed-point steps (A h^2 is tiny next to h on a flange).
double surface_h(const FlangeSurface& f, double s, double t) {
  const double base = f.A * s * s + (f.B + f.G * t) * s + f.C + f.E * t;
  double h = base;
  for (int i = 0; i < 4; ++i) h = base + f.A * h * h;
  return h;
}

// The flange's model samples on the scanned skin, as (s, t) of its frame. A solid's flange has
// both sides of the sheet; the scanned side is the one nearer the scan's points (h = 0 at their
// centroid). Its outline is the edge: the other side's may differ (a chamfer, a draft).
std::vector<Vec2> skin_samples(const PartModel& model, const Flange& flange,
                               const FlangeFrame& frame) {
  const PointCloud& s = model.samples;
  std::vector<Vec3> q;
  for (std::size_t i = 0; i < s.size(); ++i)
    if (std::find(flange.face_ids.begin(), flange.face_ids.end(), s.face_ids[i]) !=
        flange.face_ids.end())
      q.push_back(frame.local(s.points[i]));
  double h_lo = std::numeric_limits<double>::infinity(), h_hi = -h_lo;
  for (const Vec3& p : q) h_lo = std::min(h_lo, p.z()), h_hi = std::max(h_hi, p.z());
  const double mid = 0.5 * (h_lo + h_hi);
  const bool two_sides = h_hi - h_lo > 0.5 * flange.thickness_mm && flange.thickness_mm > 0.0;
  const bool upper = std::abs(h_hi) < std::abs(h_lo);
  std::vector<Vec2> out;
  out.reserve(q.size());
  for (const Vec3& p : q)
    if (!two_sides || (p.z() > mid) == upper) out.emplace_back(p.x(), p.y());
  return out;
}

double cross(const Vec2& a, const Vec2& b) { return a.x() * b.y() - a.y() * b.x(); }

// The convex hull, counter-clockwise (Andrew's monotone chain).
std::vector<Vec2> convex_hull(std::vector<Vec2> p) {
  std::sort(p.begin(), p.end(), [](const Vec2& a, const Vec2& b) {
    return a.x() < b.x() || (a.x() == b.x() && a.y() < b.y());
  });
  if (p.size() < 3) return p;
  std::vector<Vec2> hull(2 * p.size());
  std::size_t k = 0;
  for (std::size_t i = 0; i < p.size(); ++i) {  // lower hull
    while (k >= 2 && cross(hull[k - 1] - hull[k - 2], p[i] - hull[k - 2]) <= 0.0) --k;
    hull[k++] = p[i];
  }
  for (std::size_t i = p.size() - 1, lower = k + 1; i-- > 0;) {  // upper hull
    while (k >= lower && cross(hull[k - 1] - hull[k - 2], p[i] - hull[k - 2]) <= 0.0) --k;
    hull[k++] = p[i];
  }
  hull.resize(k - 1);  // the last point is the first
  return hull;
}

double angle_between(const Vec2& a, const Vec2& b) {
  return std::abs(std::atan2(cross(a, b), a.dot(b)));
}

// A straight piece of the outline: from `start` to `end`, counter-clockwise.
struct Run {
  Vec2 start, end;
};

// The hull cut into straight runs where it turns by more than `corner` (radians): each hull
// edge joins the run before it while its direction stays within `corner` of the run's chord.
// The walk starts at the sharpest corner; a hull with none (a disc) has no straight edge.
std::vector<Run> straight_runs(const std::vector<Vec2>& hull, double corner, double min_length) {
  const std::size_t m = hull.size();
  if (m < 3) return {};
  const auto edge = [&](std::size_t i) { return Vec2(hull[(i + 1) % m] - hull[i % m]); };
  std::size_t first = 0;
  double sharpest = -1.0;
  for (std::size_t i = 0; i < m; ++i) {
    const double turn = angle_between(edge(i + m - 1), edge(i));
    if (turn > sharpest) sharpest = turn, first = i;
  }
  if (sharpest < corner) return {};
  std::vector<Run> runs;
  Run run{hull[first], hull[(first + 1) % m]};
  for (std::size_t j = 1; j < m; ++j) {
    const std::size_t i = first + j;
    if (angle_between(run.end - run.start, edge(i)) <= corner) {
      run.end = hull[(i + 1) % m];
      continue;
    }
    runs.push_back(run);
    run = {hull[i % m], hull[(i + 1) % m]};
  }
  runs.push_back(run);
  std::erase_if(runs, [&](const Run& r) { return (r.end - r.start).norm() < min_length; });
  return runs;
}

bool on_a_bend(const PartSegmentation& seg, int face_id) {
  return std::any_of(seg.bends.begin(), seg.bends.end(), [face_id](const Bend& b) {
    return std::find(b.face_ids.begin(), b.face_ids.end(), face_id) != b.face_ids.end();
  });
}

// The edge as a line s = a + b t: of the lines above every point (t, s), the one with the least
// area under it over the points' span, which passes through the edge of their upper convex hull
// above the span's middle (the maximum-likelihood edge of points uniform below a straight edge).
// One far point per strip would give each strip's edge alone, with the exponential tail of the
// largest of a few hundred uniform values (a strip 0.07 mm short in 1 of 300); the line uses
// every strip's points at once.
Vec2 upper_hull_line(std::vector<Vec2> p) {
  std::sort(p.begin(), p.end(), [](const Vec2& a, const Vec2& b) {
    return a.x() < b.x() || (a.x() == b.x() && a.y() < b.y());
  });
  std::vector<Vec2> hull;
  for (const Vec2& q : p) {
    // Keep turning clockwise (the upper hull, left to right).
    while (hull.size() >= 2 &&
           cross(hull.back() - hull[hull.size() - 2], q - hull[hull.size() - 2]) >= 0.0)
      hull.pop_back();
    hull.push_back(q);
  }
  if (hull.size() < 2) return {hull.empty() ? 0.0 : hull[0].y(), 0.0};
  const double middle = 0.5 * (p.front().x() + p.back().x());
  std::size_t i = 1;
  while (i + 1 < hull.size() && hull[i].x() < middle) ++i;
  const Vec2 a = hull[i - 1], b = hull[i];
  const double slope = (b.y() - a.y()) / std::max(b.x() - a.x(), 1e-12);
  return {a.y() - slope * a.x(), slope};
}

// The points with company: those with at least half the neighbours a point of the sheet at its
// edge has within 3 point spacings (half a disc of them, rho pi r^2 / 2 = 14 at the density rho
// of the band, spacing 1 / sqrt(rho)). An outlier along a grazing ray that stays within the
// surface's inlier band lies alone beyond the edge (0.5-1.6 mm out in plane at sigma 0.05 with
// 2 % outliers, 2-5 spacings) and would carry the hull line out with it; one within 1.2
// spacings of the edge (the disc's share inside the sheet above half) stays, and moves the
// line by less than that. `p` as (t, s), sorted by t here.
std::vector<Vec2> with_company(std::vector<Vec2> p, double spacing) {
  constexpr double kRadius = 3.0;  // spacings
  const auto needed = static_cast<int>(std::ceil(0.5 * std::numbers::pi * kRadius * kRadius / 2.0));
  const double r = kRadius * spacing, r2 = r * r;
  if (!(r > 0.0 && std::isfinite(r))) return p;
  std::sort(p.begin(), p.end(), [](const Vec2& a, const Vec2& b) { return a.x() < b.x(); });
  std::vector<Vec2> kept;
  kept.reserve(p.size());
  std::size_t lo = 0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    while (p[lo].x() < p[i].x() - r) ++lo;
    int company = 0;
    for (std::size_t j = lo; j < p.size() && p[j].x() <= p[i].x() + r && company < needed; ++j)
      if (j != i && (p[j] - p[i]).squaredNorm() <= r2) ++company;
    if (company >= needed) kept.push_back(p[i]);
  }
  return kept;
}

// One candidate edge in the flange's plane: t along it (`along`), s out of the material (`out`),
// both unit 2-D vectors of the flange frame's (s, t); its extent [t0, t1].
struct EdgeLine {
  Vec2 along, out;
  double t0 = 0.0, t1 = 0.0;
  Vec2 flange_st(double s, double t) const { return s * out + t * along; }
};

struct Strip {
  double cad_s = 0.0, cad_h = 0.0;  // the CAD edge at the strip's centre
  double centre = 0.0;
  std::size_t count = 0;  // scan points in the band
};

struct EdgeInput {
  const PartModel& model;
  const FlangeShape& shape;
  const std::vector<Vec2>& samples;  // the scanned skin's model samples, flange (s, t)
  const std::vector<Vec2>& near;     // scan points on the fitted surface near the outline
  const FlangeEdgeSettings& st;
  bool solid = false;  // the flange has both sides of a sheet (a solid model)
};

// The CAD edge at each strip's centre: the closest surface point to a point in the plane 1 mm
// beyond the strip's outermost sample lies on the edge there, unless the surface goes on (a
// bend's face, or the foot not behind the query point): then this is no trim edge.
bool locate_cad_edge(const EdgeInput& in, const EdgeLine& line, std::vector<Strip>& strips) {
  const std::size_t n = strips.size();
  const double window = (line.t1 - line.t0) / static_cast<double>(n);
  std::vector<double> outermost(n, -std::numeric_limits<double>::infinity());
  for (const Vec2& p : in.samples) {
    const double k = std::floor((line.along.dot(p) - line.t0) / window);
    if (k >= 0.0 && k < static_cast<double>(n))
      outermost[static_cast<std::size_t>(k)] =
          std::max(outermost[static_cast<std::size_t>(k)], line.out.dot(p));
  }
  const FlangeFrame& frame = in.shape.frame;
  for (std::size_t k = 0; k < n; ++k) {
    if (!std::isfinite(outermost[k])) return false;
    Strip& strip = strips[k];
    strip.centre = line.t0 + (static_cast<double>(k) + 0.5) * window;
    const double beyond = outermost[k] + 1.0;
    const Vec2 q = line.flange_st(beyond, strip.centre);
    const SurfaceHit hit =
        in.model.distance->closest(frame.origin + q.x() * frame.u + q.y() * frame.d);
    if (on_a_bend(in.model.segmentation, hit.face_id)) return false;
    // On a solid, the query point inside the material (behind the foot's face: a wall that
    // rises from the skin there, a rib, a gusset) is an inside corner, where the surface turns,
    // not where the sheet ends; beyond a trim edge it lies outside, in front of the end face.
    // (A surface model has no inside: its free boundary's foot may lie off the query point's
    // height on a sprung flange, either side.)
    const Vec3 query = frame.origin + q.x() * frame.u + q.y() * frame.d;
    if (in.solid && (query - hit.foot).dot(hit.normal) < -0.5 * (query - hit.foot).norm())
      return false;
    const Vec3 foot = frame.local(hit.foot);
    strip.cad_s = line.out.dot(Vec2(foot.x(), foot.y()));
    strip.cad_h = foot.z();
    if (!(strip.cad_s <= beyond - 0.5)) return false;
  }
  return true;
}

// A straight CAD edge: the strips' feet on one line within max_edge_bend_mm. A tab, a notch or
// a curved outline is left out rather than reported against the wrong line.
bool straight(const std::vector<Strip>& strips, double tolerance) {
  Eigen::Matrix2d normal = Eigen::Matrix2d::Zero();
  Vec2 rhs = Vec2::Zero();
  for (const Strip& strip : strips) {
    const Vec2 x(1.0, strip.centre);
    normal += x * x.transpose();
    rhs += x * strip.cad_s;
  }
  const Vec2 cad_line = normal.ldlt().solve(rhs);
  return std::all_of(strips.begin(), strips.end(), [&](const Strip& strip) {
    return std::abs(strip.cad_s - cad_line[0] - cad_line[1] * strip.centre) <= tolerance;
  });
}

std::optional<EdgeDeviation> measure_edge(const EdgeInput& in, const EdgeLine& line) {
  const FlangeEdgeSettings& st = in.st;
  const double length = line.t1 - line.t0;
  const auto n = static_cast<std::size_t>(
      std::max<long>(st.min_strips, std::lround(length / st.strip_length_mm)));
  std::vector<Strip> strips(n);
  if (!locate_cad_edge(in, line, strips) || !straight(strips, st.max_edge_bend_mm))
    return std::nullopt;
  // The scan points within the band around the CAD edge, as (t, s).
  const double window = length / static_cast<double>(n);
  std::vector<Vec2> band;
  for (const Vec2& p : in.near) {
    const double t = line.along.dot(p), s = line.out.dot(p);
    const double k = std::floor((t - line.t0) / window);
    if (!(k >= 0.0 && k < static_cast<double>(n))) continue;
    Strip& strip = strips[static_cast<std::size_t>(k)];
    if (s < strip.cad_s - st.band_mm || s > strip.cad_s + st.band_mm) continue;
    band.emplace_back(t, s);
    ++strip.count;
  }
  // Every strip must see the edge: a strip the scan does not reach (occlusion, a missing area)
  // would leave the straight line to the others' points and report an edge nobody saw.
  const auto min_count = static_cast<std::size_t>(std::max(st.min_points_per_strip, 2));
  if (std::any_of(strips.begin(), strips.end(),
                  [&](const Strip& s) { return s.count < min_count; }))
    return std::nullopt;
  // The line of the hull lies below the edge by about one point's share of the band's area
  // spread over its length: band_mm / n.
  // The band's points lie inside the sheet, band_mm deep: its density gives the spacing.
  // (The spacing first: the order in which a call's arguments are evaluated is unspecified, and
  // clang moved `band` out before reading its size, a spacing of 1/0.)
  const double spacing = std::sqrt(length * st.band_mm / static_cast<double>(band.size()));
  band = with_company(std::move(band), spacing);
  if (band.size() < min_count) return std::nullopt;
  Vec2 scan_line = upper_hull_line(band);
  scan_line[0] += st.band_mm / static_cast<double>(band.size());
  const FlangeFrame& frame = in.shape.frame;
  const auto to_3d = [&](const Vec2& v) { return Vec3(v.x() * frame.u + v.y() * frame.d); };
  EdgeDeviation e;
  e.direction = to_3d(line.along);
  e.outward = to_3d(line.out);
  e.length_mm = length;
  e.in_plane_min_mm = e.across_min_mm = std::numeric_limits<double>::infinity();
  e.in_plane_max_mm = e.across_max_mm = -std::numeric_limits<double>::infinity();
  for (const Strip& strip : strips) {
    const double edge = scan_line[0] + scan_line[1] * strip.centre;
    const double in_plane = edge - strip.cad_s;
    const Vec2 at = line.flange_st(edge, strip.centre);
    const double across = surface_h(in.shape.surface, at.x(), at.y()) - strip.cad_h;
    e.in_plane_mean_mm += in_plane / static_cast<double>(n);
    e.across_mean_mm += across / static_cast<double>(n);
    e.in_plane_min_mm = std::min(e.in_plane_min_mm, in_plane);
    e.in_plane_max_mm = std::max(e.in_plane_max_mm, in_plane);
    e.across_min_mm = std::min(e.across_min_mm, across);
    e.across_max_mm = std::max(e.across_max_mm, across);
    const auto point = [&](double s, double h) {
      return Vec3(frame.origin + to_3d(line.flange_st(s, strip.centre)) + h * frame.n);
    };
    e.cad_edge.push_back(point(strip.cad_s, strip.cad_h));
    e.scan_edge.push_back(point(edge, strip.cad_h + across));
  }
  e.strips = static_cast<int>(n);
  e.measured = true;
  return e;
}

// The scan points in use on the fitted surface (within its inlier threshold) and within
// band_mm of the samples' box, as the flange frame's (s, t): one pass for all its edges.
std::vector<Vec2> points_near_outline(const FlangeShape& shape, const std::vector<Vec2>& samples,
                                      const PointCloud& scan, std::span<const std::uint32_t> points,
                                      double band_mm) {
  Vec2 lo = Vec2::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  for (const Vec2& p : samples) lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
  lo.array() -= band_mm;
  hi.array() += band_mm;
  std::vector<Vec2> near;
  for (std::uint32_t i : points) {
    const Vec3 q = shape.frame.local(scan.points[i]);
    if (q.x() < lo.x() || q.x() > hi.x() || q.y() < lo.y() || q.y() > hi.y()) continue;
    if (std::abs(q.z() - surface_h(shape.surface, q.x(), q.y())) <= shape.inlier_threshold_mm)
      near.emplace_back(q.x(), q.y());
  }
  return near;
}

}  // namespace

std::string_view edge_kind_name(EdgeKind kind) { return kind == EdgeKind::kFree ? "free" : "side"; }

std::vector<EdgeDeviation> measure_trim_edges(const PartModel& model, const Flange& flange,
                                              const FlangeShape& shape, const Bend* end_bend,
                                              const PointCloud& scan,
                                              std::span<const std::uint32_t> points,
                                              const FlangeEdgeSettings& st) {
  std::vector<EdgeDeviation> edges;
  if (!shape.measured || !model.distance || !model.samples.has_face_ids() ||
      !(st.strip_length_mm > 0.0))
    return edges;
  const FlangeFrame& frame = shape.frame;
  const std::vector<Vec2> samples = skin_samples(model, flange, frame);
  const double corner = st.corner_angle_deg * std::numbers::pi / 180.0;
  const std::vector<Run> runs =
      straight_runs(convex_hull(samples), corner, std::max(st.min_edge_length_mm, 1e-9));
  if (runs.empty()) return edges;
  const std::vector<Vec2> near = points_near_outline(shape, samples, scan, points, st.band_mm);
  const EdgeInput in{model, shape, samples, near, st, flange.thickness_mm > 0.0};
  for (const Run& run : runs) {
    EdgeLine line;
    line.along = (run.end - run.start).normalized();
    line.out = Vec2(line.along.y(), -line.along.x());  // right of a counter-clockwise outline
    line.t0 = line.along.dot(run.start);
    line.t1 = line.along.dot(run.end);
    std::optional<EdgeDeviation> e = measure_edge(in, line);
    if (!e) continue;
    // The free edge: parallel to the end flange's bend, on the side of the centroid away
    // from it.
    if (end_bend) {
      const Vec3 axis = end_bend->axis_direction.normalized();
      const Vec3 to_bend = frame.local(end_bend->axis_point);
      const double parallel = std::abs(axis.dot(e->direction));
      if (parallel >= std::cos(corner) && line.out.dot(Vec2(to_bend.x(), to_bend.y())) < 0.0)
        e->kind = EdgeKind::kFree;
    }
    edges.push_back(std::move(*e));
  }
  return edges;
}

}  // namespace springscan::analysis
