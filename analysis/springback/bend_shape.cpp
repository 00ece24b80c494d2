// Beyond rigid flanges (bend_shape.hpp, docs/springback.md): flange shape, bend zone cylinder,
// the angle along the bend and the end-tangent angle next to a curled flange. Everything works
// on the points measure_springback already assigned (thinned), in a few linear passes.
#include "analysis/springback/bend_shape.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <unordered_map>

#include "analysis/core/parallel.hpp"

namespace springscan::analysis {
namespace {

// The first bend (segmentation order) that touches the flange: its axis is the flange's bend
// line, along which twist and stations are measured.
const Bend* first_bend_of(const PartSegmentation& seg, int flange_id) {
  for (const Bend& b : seg.bends)
    if (b.flange_a == flange_id || b.flange_b == flange_id) return &b;
  return nullptr;
}

// The number of bends that touch the flange: an end flange has one, and a free edge opposite.
int bends_of(const PartSegmentation& seg, int flange_id) {
  return static_cast<int>(std::count_if(seg.bends.begin(), seg.bends.end(), [&](const Bend& b) {
    return b.flange_a == flange_id || b.flange_b == flange_id;
  }));
}

// The points of a flange on one skin. On a solid the scan may see both skins of a flange (two
// passes from either side of a standing wall), a thickness apart: a shape fitted to both would
// take the step for flatness and curl. The skin with more points is kept; on a surface model
// (no thickness) all points.
std::vector<std::uint32_t> one_skin(const PointCloud& scan,
                                    const std::vector<std::uint32_t>& points,
                                    const Flange& flange) {
  const double t = flange.thickness_mm;
  if (!(t > 0.0)) return points;
  std::vector<std::uint32_t> near, far;
  for (std::uint32_t i : points) {
    const double h = flange.normal.dot(scan.points[i] - flange.point);
    (std::abs(h) < 0.5 * t ? near : far).push_back(i);
  }
  return near.size() >= far.size() ? near : far;
}

// Flange f's shape in the frame of its bend line, and its trim edges.
void fit_flange_shape_of(const PartModel& model, const PointCloud& scan,
                         const std::vector<std::uint32_t>& points, const BendShapeSettings& st,
                         std::size_t f, SpringbackResult& result) {
  const PartSegmentation& seg = model.segmentation;
  const Flange& flange = seg.flanges[f];
  FlangeFit& fit = result.flanges[f];
  const Bend* bend = first_bend_of(seg, flange.id);
  fit.has_bend_line = bend != nullptr;
  const Vec3 along = bend ? bend->axis_direction : flange.normal.unitOrthogonal();
  const std::vector<std::uint32_t> skin = one_skin(scan, fit.indices, flange);
  const FlangeFrame frame = flange_frame(scan, skin, flange.normal, along);
  fit.shape =
      fit_flange_shape(scan, skin, frame, st.flange,
                       fit.fitted ? fit.fit.rms_mm : std::numeric_limits<double>::infinity());
  if (!fit.has_bend_line) {  // no direction across: a curl radius or a twist means nothing
    fit.shape.curled = false;
    fit.shape.surface.A = 0.0;
    fit.shape.curl_radius_mm = std::numeric_limits<double>::infinity();
    fit.shape.twist_deg_per_100mm = 0.0;
    fit.shape.twist_measured = false;
  }
  const Bend* end_bend = bend && bends_of(seg, flange.id) == 1 ? bend : nullptr;
  fit.trim_edges = measure_trim_edges(model, flange, fit.shape, end_bend, scan, points, st.edge);
}

// The flange's end normal next to the bend on the bend's concave side (the side its nominal
// turn is measured on, springback.cpp).
Vec3 concave_end_normal(const Flange& flange, const Bend& bend, const FlangeShape& shape,
                        const FlangeSurface& surface, const Vec3& near) {
  const Vec3 n = end_normal(shape.frame, surface, near);
  return concave_normal(flange, bend).dot(shape.frame.n) < 0.0 ? Vec3(-n) : n;
}

struct BendContext {
  const Bend& bend;
  const Flange& fa;
  const Flange& fb;
  const FlangeFit& a;
  const FlangeFit& b;
  double nominal_turn_deg;  // between the concave-side CAD normals
};

// The measured axis at `position` along the bend (the zone's cylinder; the nominal axis when
// the zone could not be fitted).
Vec3 axis_at(const BendMeasurement& m, double position) {
  return m.zone.fitted ? m.zone.axis_at(position) : m.axis_point + position * m.axis_direction;
}

// Strip fits of both flanges at stations along the bend: one pass over each flange's points.
void measure_stations(const BendContext& c, double t_lo, double t_hi, const BendShapeSettings& st,
                      BendMeasurement& m) {
  const double length = t_hi - t_lo;
  if (!(length > 0.0) || !(st.station_spacing_mm > 0.0)) return;
  const auto n = static_cast<std::size_t>(
      std::max<long>(st.min_stations, std::lround(length / st.station_spacing_mm)));
  const double window = length / static_cast<double>(n);
  const auto centre = [&](std::size_t k) { return t_lo + (static_cast<double>(k) + 0.5) * window; };
  const auto strips = [&](const FlangeFit& f) {
    std::vector<StripFit> out;
    for (std::size_t k = 0; k < n; ++k) {
      const double t = f.shape.frame.local(m.axis_point + centre(k) * m.axis_direction).y();
      out.emplace_back(f.shape.surface, t);
    }
    // The position along the bend is linear in the frame coordinates: one dot product.
    const FlangeFrame& fr = f.shape.frame;
    const Vec3& a = m.axis_direction;
    const Vec3 along(fr.u.dot(a), fr.d.dot(a), fr.n.dot(a));
    const double offset = (fr.origin - m.axis_point).dot(a) - t_lo;
    for (std::size_t j = 0; j < f.shape.local.size(); ++j) {
      if (!f.shape.inlier[j]) continue;
      const Vec3& q = f.shape.local[j];
      const double k = std::floor((offset + along.dot(q)) / window);
      if (k >= 0.0 && k < static_cast<double>(n)) out[static_cast<std::size_t>(k)].add(q);
    }
    return out;
  };
  const auto sa = strips(c.a), sb = strips(c.b);
  const auto enough = static_cast<std::size_t>(std::max(st.min_points_per_station, 6));
  for (std::size_t k = 0; k < n; ++k) {
    FlangeSurface fa, fb;
    if (sa[k].points() < enough || sb[k].points() < enough || !sa[k].solve(fa) || !sb[k].solve(fb))
      continue;
    const Vec3 near = axis_at(m, centre(k));
    const Vec3 na = concave_end_normal(c.fa, c.bend, c.a.shape, fa, near);
    const Vec3 nb = concave_end_normal(c.fb, c.bend, c.b.shape, fb, near);
    const double springback = wrapped_deg(c.nominal_turn_deg - turn_deg(na, nb, m.axis_direction));
    m.stations.push_back({centre(k), m.nominal_angle_deg - springback, springback});
  }
  if (m.stations.empty()) return;
  const auto [lo, hi] = std::minmax_element(
      m.stations.begin(), m.stations.end(),
      [](const BendStation& x, const BendStation& y) { return x.angle_deg < y.angle_deg; });
  m.angle_min_deg = lo->angle_deg;
  m.angle_max_deg = hi->angle_deg;
  m.angle_spread_deg = hi->angle_deg - lo->angle_deg;
  m.angle_twist_deg = m.stations.back().angle_deg - m.stations.front().angle_deg;
}

// Next to a curled flange, the plane through the whole flange is not the flange's direction
// at the bend: the bend angle is taken between the tangent planes at the flanges' ends next to
// it (NUMISHEET'93), at the middle of the bend.
void end_tangent_angle(const BendContext& c, double t_mid, BendMeasurement& m) {
  if (!(c.a.shape.curled || c.b.shape.curled)) return;
  const Vec3 near = axis_at(m, t_mid);
  const Vec3 na = concave_end_normal(c.fa, c.bend, c.a.shape, c.a.shape.surface, near);
  const Vec3 nb = concave_end_normal(c.fb, c.bend, c.b.shape, c.b.shape.surface, near);
  m.springback_deg = wrapped_deg(c.nominal_turn_deg - turn_deg(na, nb, m.axis_direction));
  m.measured_angle_deg = m.nominal_angle_deg - m.springback_deg;
  m.end_tangents = true;
}

// The zone's points between the two tangent lines, as the fitted cylinder and the flanges'
// end planes place them. Where the bend turns less than the CAD's, the CAD's bend zone reaches
// onto the flanges' straight ends; those points lie outside the circle by d^2 / 2R (d beyond
// the tangent line) and pull the cylinder outwards. Decided by angle around the axis, which
// radial noise hardly moves: a test on the distance from a flange would keep the points whose
// noise happens to lie inwards, and shrink the radius.
std::vector<std::uint32_t> within_wedge(const std::vector<std::uint32_t>& points,
                                        const BendContext& c, const BendMeasurement& m,
                                        const PointCloud& scan) {
  constexpr double kMarginMm = 0.1;  // of arc, inside each tangent line
  const double margin = kMarginMm / std::max(m.zone.radius_mm, 0.1);
  std::vector<std::uint32_t> out;
  out.reserve(points.size());
  const Vec3 axis = m.zone.axis_direction;
  const auto across = [&axis](const Vec3& v) { return (v - v.dot(axis) * axis).normalized(); };
  for (std::uint32_t i : points) {
    const Vec3& p = scan.points[i];
    const Vec3 centre = m.zone.axis_at((p - m.axis_point).dot(m.axis_direction));
    // From the axis, each tangent line lies against its flange's concave-side normal.
    const Vec3 ta = across(-concave_end_normal(c.fa, c.bend, c.a.shape, c.a.shape.surface, centre));
    const Vec3 tb = across(-concave_end_normal(c.fb, c.bend, c.b.shape, c.b.shape.surface, centre));
    const Vec3 r = across(p - centre);
    const double sweep = std::acos(std::clamp(ta.dot(tb), -1.0, 1.0));
    const double from_a = std::acos(std::clamp(ta.dot(r), -1.0, 1.0));
    const double from_b = std::acos(std::clamp(tb.dot(r), -1.0, 1.0));
    if (from_a >= margin && from_b >= margin && from_a <= sweep && from_b <= sweep)
      out.push_back(i);
  }
  return out;
}

// The cylinder of the zone: fitted to all its points, then twice to those between the
// tangent lines of the flanges as measured.
BendZoneFit fit_zone(const std::vector<std::uint32_t>& points, const BendContext& c,
                     const BendMeasurement& m, const PointCloud& scan, const BendZoneSettings& st) {
  BendMeasurement trial = m;
  trial.zone = fit_bend_zone(scan, points, m.axis_point, m.axis_direction, st);
  if (!c.a.shape.measured || !c.b.shape.measured) return trial.zone;
  for (int round = 0; round < 2 && trial.zone.fitted; ++round)
    trial.zone = fit_bend_zone(scan, within_wedge(points, c, trial, scan), m.axis_point,
                               m.axis_direction, st);
  return trial.zone;
}

// The zone of the bend with the most scan points: one side of the sheet.
std::size_t best_zone(const BendZones& zones, const std::vector<std::vector<std::uint32_t>>& pts,
                      std::size_t bend) {
  std::size_t best = zones.zones.size();
  for (std::size_t z = 0; z < zones.zones.size(); ++z)
    if (zones.zones[z].bend == bend &&
        (best == zones.zones.size() || pts[z].size() > pts[best].size()))
      best = z;
  return best;
}

// The zone cylinder, the stations and the end-tangent angle of bend b.
void measure_bend_shape(const PartModel& model, const PointCloud& scan, const BendZones& zones,
                        const std::vector<std::vector<std::uint32_t>>& zone_points,
                        const BendShapeSettings& st, std::size_t b, SpringbackResult& result) {
  const auto& seg = model.segmentation;
  const auto index_of = [&seg](int id) {
    const auto it = std::find_if(seg.flanges.begin(), seg.flanges.end(),
                                 [id](const Flange& f) { return f.id == id; });
    return static_cast<std::size_t>(it - seg.flanges.begin());
  };
  const Bend& bend = seg.bends[b];
  BendMeasurement& m = result.bends[b];
  const std::size_t ia = index_of(bend.flange_a), ib = index_of(bend.flange_b);
  const BendContext c{bend,
                      seg.flanges[ia],
                      seg.flanges[ib],
                      result.flanges[ia],
                      result.flanges[ib],
                      turn_deg(concave_normal(seg.flanges[ia], bend),
                               concave_normal(seg.flanges[ib], bend), m.axis_direction)};
  if (const std::size_t z = best_zone(zones, zone_points, b); z < zones.zones.size()) {
    m.zone = fit_zone(zone_points[z], c, m, scan, st.zone);
    // The fitted side's radius, less that side's nominal offset from the inner radius.
    if (m.zone.fitted)
      m.measured_radius_mm = m.zone.radius_mm - (zones.zones[z].nominal_radius_mm - m.radius_mm);
  }
  if (!m.measured || !c.a.shape.measured || !c.b.shape.measured) return;
  // The bend's extent along its oriented axis.
  const bool flipped = m.axis_direction.dot(bend.axis_direction) < 0.0;
  const double lo = flipped ? -zones.t_max[b] : zones.t_min[b];
  const double hi = flipped ? -zones.t_min[b] : zones.t_max[b];
  if (!(std::isfinite(lo) && std::isfinite(hi))) return;  // a bend without samples
  measure_stations(c, lo, hi, st, m);
  end_tangent_angle(c, 0.5 * (lo + hi), m);
}

}  // namespace

BendZones label_bend_zones(const PartModel& model, std::vector<std::int32_t>& labels) {
  const auto& seg = model.segmentation;
  BendZones out;
  std::unordered_map<int, std::size_t> zone_of_face;
  for (std::size_t b = 0; b < seg.bends.size(); ++b)
    for (int face : seg.bends[b].face_ids)
      if (zone_of_face.emplace(face, out.zones.size()).second) out.zones.push_back({b, face, 0.0});
  out.t_min.assign(seg.bends.size(), std::numeric_limits<double>::infinity());
  out.t_max.assign(seg.bends.size(), -std::numeric_limits<double>::infinity());
  std::vector<std::size_t> count(out.zones.size(), 0);
  const auto base = static_cast<std::int32_t>(seg.flanges.size());
  const PointCloud& s = model.samples;
  for (std::size_t i = 0; i < s.size(); ++i) {
    const auto it = zone_of_face.find(s.face_ids[i]);
    if (it == zone_of_face.end()) continue;
    BendZones::Zone& zone = out.zones[it->second];
    const Bend& bend = seg.bends[zone.bend];
    labels[i] = base + static_cast<std::int32_t>(it->second);
    const Vec3 d = s.points[i] - bend.axis_point;
    const Vec3 axis = bend.axis_direction.normalized();
    const double t = d.dot(axis);
    zone.nominal_radius_mm += (d - t * axis).norm();
    ++count[it->second];
    out.t_min[zone.bend] = std::min(out.t_min[zone.bend], t);
    out.t_max[zone.bend] = std::max(out.t_max[zone.bend], t);
  }
  for (std::size_t z = 0; z < out.zones.size(); ++z)
    if (count[z] > 0) out.zones[z].nominal_radius_mm /= static_cast<double>(count[z]);
  return out;
}

void measure_shapes(const PartModel& model, const PointCloud& scan,
                    const std::vector<std::uint32_t>& points, const BendZones& zones,
                    const std::vector<std::vector<std::uint32_t>>& zone_points,
                    const BendShapeSettings& st, int threads, SpringbackResult& result) {
  const auto& seg = model.segmentation;
  // Flanges, then bends, one task each: each writes only its own record.
  for_each_block(seg.flanges.size(), 1, threads, [&](std::size_t, std::size_t f, std::size_t) {
    fit_flange_shape_of(model, scan, points, st, f, result);
  });
  for_each_block(seg.bends.size(), 1, threads, [&](std::size_t, std::size_t b, std::size_t) {
    measure_bend_shape(model, scan, zones, zone_points, st, b, result);
  });
}

}  // namespace springscan::analysis
