// The uncertainty stage (uncertainty.hpp, docs/uncertainty.md): GUM propagation from each
// flange's own points, the method's residual error and the station's terms.
#include "analysis/uncertainty/uncertainty.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "analysis/uncertainty/fit_covariance.hpp"
#include "analysis/uncertainty/frame_uncertainty.hpp"

namespace springscan::analysis {
namespace {

constexpr double kRadToDeg = 180.0 / std::numbers::pi;
// Where a curled flange's end tangent is taken, to about this (standard, mm): the calibration
// study's curled walls (docs/uncertainty.md) show end-tangent errors of 0.05-0.25 mm over R.
constexpr double kTangentPointMm = 0.1;

// One flange's fits as the uncertainty sees them.
struct FlangeModel {
  const FlangeFit* fit = nullptr;
  std::vector<std::uint8_t> inlier;  // the points its plane is made of (per shape.local)
  double band_mm = 0.0;              // their band about the plane (the shape's inlier threshold)
  // The shape's points are not the skin the local fit measured (see estimate_uncertainty): the
  // tilt is judged from the fit's own points and residual.
  bool foreign_points = false;
  PlaneCovariance plane;
  CurlCovariance curl;  // curled flanges only
  bool ok = false;
};

double sq(double x) { return x * x; }

// Root sum of squares.
double rss(std::initializer_list<double> terms) {
  double sum = 0.0;
  for (double t : terms) sum += t * t;
  return std::sqrt(sum);
}

// The lower median of the flanges' plane residuals: the part's point noise as the fits see it
// (a flange that departs from its plane only raises the upper half).
double part_noise(const std::vector<FlangeModel>& flanges) {
  std::vector<double> sigma;
  for (const FlangeModel& f : flanges)
    if (f.ok) sigma.push_back(f.curl.ok ? f.curl.sigma_mm : f.plane.sigma_mm);
  if (sigma.empty()) return 0.0;
  std::sort(sigma.begin(), sigma.end());
  return sigma[(sigma.size() - 1) / 2];
}

// Narrows `model.inlier` to the points of the flange's plane: rounds of a least-squares plane
// and a band of 3 robust sigmas (1.4826 MAD) of its residuals, as the local fit rejects what
// lies off its plane. The plane's covariance is then of those points.
void keep_plane_points(const FlangeShape& shape, FlangeModel& model) {
  constexpr int kRounds = 4;
  std::vector<double> residual(shape.local.size());
  std::vector<double> magnitude;
  for (int round = 0; round < kRounds; ++round) {
    Eigen::Matrix3d normal = Eigen::Matrix3d::Zero();
    Eigen::Vector3d rhs = Eigen::Vector3d::Zero();
    for (std::size_t j = 0; j < shape.local.size(); ++j) {
      if (!model.inlier[j]) continue;
      const Eigen::Vector3d x(1.0, shape.local[j].x(), shape.local[j].y());
      normal += x * x.transpose();
      rhs += x * shape.local[j].z();
    }
    const Eigen::LDLT<Eigen::Matrix3d> ldlt(normal);
    if (normal(0, 0) < 12.0 || ldlt.info() != Eigen::Success || !ldlt.isPositive()) return;
    const Eigen::Vector3d beta = ldlt.solve(rhs);
    magnitude.clear();
    for (std::size_t j = 0; j < shape.local.size(); ++j) {
      const Vec3& q = shape.local[j];
      residual[j] = q.z() - (beta(0) + beta(1) * q.x() + beta(2) * q.y());
      if (model.inlier[j]) magnitude.push_back(std::abs(residual[j]));
    }
    const auto mid = magnitude.begin() + static_cast<long>(magnitude.size() / 2);
    std::nth_element(magnitude.begin(), mid, magnitude.end());
    const double band = 3.0 * 1.4826 * *mid;
    if (!(band > 0.0)) return;
    std::size_t kept = 0;
    for (std::size_t j = 0; j < shape.local.size(); ++j)
      kept += shape.inlier[j] && std::abs(residual[j]) <= band ? 1 : 0;
    if (kept < 12) return;
    for (std::size_t j = 0; j < shape.local.size(); ++j)
      model.inlier[j] = shape.inlier[j] && std::abs(residual[j]) <= band ? 1 : 0;
    model.band_mm = band;
  }
  const PlaneCovariance plane = plane_covariance(shape.local, model.inlier);
  if (plane.ok) model.plane = plane;
}

// The unit in-plane direction across a bend with axis `axis`, in the flange's (s, t) frame.
Eigen::Vector2d across_in_frame(const FlangeFrame& frame, const Vec3& axis) {
  const Vec3 across = frame.n.cross(axis);
  const Eigen::Vector2d w(across.dot(frame.u), across.dot(frame.d));
  return w.norm() > 1e-9 ? Eigen::Vector2d(w.normalized()) : Eigen::Vector2d(1.0, 0.0);
}

// The least-squares slope along w (unit, in (s, t)) of h = c + b_s s + b_t t over the inliers
// for which `keep` holds; NaN when they do not fix it.
template <typename Keep>
double plane_slope(const FlangeModel& f, const Eigen::Vector2d& w, Keep keep) {
  const FlangeShape& shape = f.fit->shape;
  Eigen::Matrix3d normal = Eigen::Matrix3d::Zero();
  Eigen::Vector3d rhs = Eigen::Vector3d::Zero();
  for (std::size_t j = 0; j < shape.local.size(); ++j) {
    const Vec3& q = shape.local[j];
    if (!f.inlier[j] || !keep(q)) continue;
    const Eigen::Vector3d x(1.0, q.x(), q.y());
    normal += x * x.transpose();
    rhs += x * q.z();
  }
  const Eigen::LDLT<Eigen::Matrix3d> ldlt(normal);
  if (normal(0, 0) < 6.0 || ldlt.info() != Eigen::Success || !ldlt.isPositive())
    return std::numeric_limits<double>::quiet_NaN();
  const Eigen::Vector3d beta = ldlt.solve(rhs);
  return beta(1) * w.x() + beta(2) * w.y();
}

// How much a flange's tilt across a bend rests on its points next to the bend (rad): the slope
// with them less the slope without the strip of the arc a skin's inlier band can hold, a =
// sqrt(2 R b) for the bend's radius R (up to a solid's thickness more) and the band b, widened
// by half. Where the flange's assignment reaches into the bend's arc, those points lie on one
// side of the plane at its end and tilt it toward the bend: a bias of one sign that grows with
// the band (the noise), which the covariance does not see (the laser-scanned solids at sigma
// 0.05 mm with outliers showed +0.015-0.02 deg, docs/uncertainty.md). Where the points stop
// short of the arc, the difference is only the noise's (about 0.4 of the tilt's own sigma).
struct EndStrip {
  double tilt_rad = 0.0;
  std::vector<std::uint8_t> inner;  // the plane's points without the strip (empty: not cut)
};

EndStrip end_strip(const FlangeModel& f, const Eigen::Vector2d& w, const Vec3& axis_point,
                   double radius_mm) {
  EndStrip out;
  const FlangeShape& shape = f.fit->shape;
  const Eigen::Vector2d mid(shape.frame.local(axis_point).x(), shape.frame.local(axis_point).y());
  // Along w toward the bend: the strip is the points within a of the flange's extreme there.
  double mean = 0.0, lo = std::numeric_limits<double>::infinity(), hi = -lo, count = 0.0;
  for (std::size_t j = 0; j < shape.local.size(); ++j) {
    if (!f.inlier[j]) continue;
    const double q = w.x() * shape.local[j].x() + w.y() * shape.local[j].y();
    mean += q, lo = std::min(lo, q), hi = std::max(hi, q), count += 1.0;
  }
  if (count < 12.0) return out;
  mean /= count;
  const double toward = w.dot(mid) >= mean ? 1.0 : -1.0;
  constexpr double kThicknessMm = 2.0;  // a solid's outer skin bends about R + t
  const double band = f.band_mm;
  const double a = std::min(std::max(1.5 * std::sqrt(2.0 * (radius_mm + kThicknessMm) * band), 1.0),
                            0.25 * (hi - lo));
  const double end = toward > 0.0 ? hi : lo;
  const auto inner = [&](const Vec3& q) {
    return toward * (end - (w.x() * q.x() + w.y() * q.y())) > a;
  };
  const double all = plane_slope(f, w, [](const Vec3&) { return true; });
  const double cut = plane_slope(f, w, inner);
  if (!std::isfinite(all) || !std::isfinite(cut)) return out;
  out.tilt_rad = std::abs(all - cut);
  out.inner = f.inlier;
  for (std::size_t j = 0; j < shape.local.size(); ++j)
    if (out.inner[j] && !inner(shape.local[j])) out.inner[j] = 0;
  return out;
}

struct Tilt {
  double fit_var = std::numeric_limits<double>::infinity();  // rad^2, from the points' noise
  double shape_rad = 0.0;        // the method's error: residual above the noise, as a whole tilt
  double end_tangent_rad = 0.0;  // the method's error of an end tangent on a curled flange
  double end_strip_rad = 0.0;    // the plane's dependence on its points next to the bend
};

// How well flange f fixes its tilt across a bend of axis `axis` (through `axis_point`): its
// plane, or the end tangent of its curl when the bend is measured by end tangents.
Tilt flange_tilt(const FlangeModel& f, const Vec3& axis, const Vec3& axis_point, bool end_tangent,
                 double floor_sigma, double radius_mm) {
  Tilt out;
  if (!f.ok) return out;
  const FlangeShape& shape = f.fit->shape;
  const Eigen::Vector2d w = across_in_frame(shape.frame, axis);
  if (f.foreign_points) {
    // The local fit's line-fit slope error (springback.cpp tilt_sigma_rad): its rms over the
    // root of its points' squared spread across the bend; the shape's points give no method
    // term here.
    const Vec3 across = f.fit->measured_normal.cross(axis);
    const double spread2 =
        across.norm() > 1e-9 ? across.normalized().dot(f.fit->spread * across.normalized()) : 0.0;
    out.fit_var = spread2 > 0.0 ? sq(std::max(f.fit->fit.rms_mm, floor_sigma)) / spread2
                                : std::numeric_limits<double>::infinity();
    out.shape_rad = 0.0;
    return out;
  }
  const bool curl = end_tangent && shape.curled && f.curl.ok;
  const double sigma = curl ? f.curl.sigma_mm : f.plane.sigma_mm;
  const double used = std::max(sigma, floor_sigma);
  if (curl) {
    const double s_end = shape.frame.local(axis_point).x();
    out.fit_var = sq(w.x()) * f.curl.slope_s_variance(s_end, 0.0, used) +
                  sq(w.y()) * f.curl.slope_t_variance(s_end, used);
    // The method's own error: the end tangent is taken where the section meets the bend, a
    // point the study (docs/uncertainty.md) finds placed to about kTangentPointMm, which turns
    // the tangent by that over the curl radius.
    out.end_tangent_rad = kTangentPointMm / std::abs(shape.curl_radius_mm);
  } else {
    out.fit_var = f.plane.slope_variance(w, used);
  }
  // The bow below is judged without the end strip: arc points there are the strip's term, and
  // the curl model would take their step for a curvature of the whole flange.
  const auto bow = [&](const PlaneCovariance& plane, const CurlCovariance& curl_fit) {
    if (curl || !curl_fit.ok) return 0.0;
    const double n = static_cast<double>(curl_fit.points);
    return std::sqrt(std::max(
        0.0, sq(plane.sigma_mm) - sq(curl_fit.sigma_mm) * (1.0 + 3.0 * std::sqrt(2.0 / n))));
  };
  PlaneCovariance plane = f.plane;
  double systematic = bow(f.plane, f.curl);
  if (!curl) {
    const EndStrip strip = end_strip(f, w, axis_point, radius_mm);
    out.end_strip_rad = strip.tilt_rad;
    if (systematic > 0.0 && !strip.inner.empty()) {  // (the inner fits only where they tell)
      const PlaneCovariance inner_plane = plane_covariance(shape.local, strip.inner);
      const CurlCovariance inner_curl = curl_covariance(shape.local, strip.inner);
      if (inner_plane.ok && inner_curl.ok)
        plane = inner_plane, systematic = bow(inner_plane, inner_curl);
    }
  }
  // A bow the plane does not follow (a curl too slight to be told, whose angle the end tangents
  // would define): what the curl model explains of the plane's residual variance, beyond what
  // the variance estimate's own scatter explains (3 of its standard errors, sqrt(2 / n)
  // relative). Not against other flanges' noise: a laser's noise along its beam differs from
  // flange to flange with the view. Correlated over the flange, its error does not shrink with
  // the point count. A residual of rms r over a spread of rms S turns the end from the plane by
  // up to 3.9 r / S (a parabola); the study's curled walls turn by up to 1.1x that: u = 2.75 r / S.
  constexpr double kBowFactor = 2.75;
  const double spread = plane.spread_mm(w);
  out.shape_rad =
      spread > 0.0 ? kBowFactor * systematic / spread : std::numeric_limits<double>::infinity();
  return out;
}

// The station terms of an angle (degrees, standard): the calibration's angle, and its length
// error over the part's extent as a turn.
double station_angle_deg(const UncertaintySettings& st, double extent_mm) {
  const double length_turn =
      extent_mm > 0.0 ? st.calibration_length_mm / extent_mm * kRadToDeg : 0.0;
  return rss({st.calibration_angle_deg, length_turn});
}

// Station k's strip of a flange: points whose position along the axis lies within half a window.
double strip_tilt_var(const FlangeModel& f, const BendMeasurement& m, double position,
                      double window, double floor_sigma) {
  if (!f.ok) return std::numeric_limits<double>::infinity();
  const FlangeShape& shape = f.fit->shape;
  const FlangeFrame& fr = shape.frame;
  const Vec3& a = m.axis_direction;
  const Vec3 along(fr.u.dot(a), fr.d.dot(a), fr.n.dot(a));
  const double offset = (fr.origin - m.axis_point).dot(a) - position;
  // A curled flange's strips hold its curvature (StripFit): the curl term comes off first, and
  // the curvature's own error is added below.
  const double A = shape.curled ? shape.surface.A : 0.0;
  std::vector<Vec3> points;  // the strip's inliers, the held curl term off h
  for (std::size_t j = 0; j < shape.local.size(); ++j) {
    const Vec3& q = shape.local[j];
    if (!f.inlier[j] || !(std::abs(offset + along.dot(q)) <= 0.5 * window)) continue;
    points.emplace_back(q.x(), q.y(), q.z() - A * (q.x() * q.x() + q.z() * q.z()));
  }
  const PlaneCovariance strip = plane_covariance(points, {});
  if (!strip.ok) return std::numeric_limits<double>::infinity();
  const Eigen::Vector2d w = across_in_frame(fr, a);
  double var = strip.slope_variance(w, std::max(strip.sigma_mm, floor_sigma));
  if (A != 0.0 && f.curl.ok) {
    const double s_end = fr.local(m.axis_point).x();
    var += sq(2.0 * s_end) * f.curl.a_variance(std::max(f.curl.sigma_mm, floor_sigma));
  }
  return var;
}

// The stations' window along the bend: the least gap between neighbouring stations (their
// centres lie a whole number of windows apart), or the whole flange for a single station.
double station_window(const BendMeasurement& m) {
  double window = std::numeric_limits<double>::infinity();
  for (std::size_t k = 1; k < m.stations.size(); ++k)
    window = std::min(window, m.stations[k].position_mm - m.stations[k - 1].position_mm);
  return window;
}

BendBudget bend_budget(const BendMeasurement& m, const FlangeModel& a, const FlangeModel& b,
                       double extent_mm, const UncertaintySettings& st) {
  BendBudget out;
  const Vec3 axis = m.axis_direction.normalized();
  const double floor_sigma = st.scanner_sigma_mm;
  const double radius = m.zone.fitted && m.measured_radius_mm > 0.0 ? m.measured_radius_mm
                                                                    : std::max(m.radius_mm, 0.0);
  const Tilt ta = flange_tilt(a, axis, m.axis_point, m.end_tangents, floor_sigma, radius);
  const Tilt tb = flange_tilt(b, axis, m.axis_point, m.end_tangents, floor_sigma, radius);
  out.fit_deg = std::sqrt(ta.fit_var + tb.fit_var) * kRadToDeg;
  // Flanges whose shape was not measured (too few points): the stage's own estimate, no less.
  if (!std::isfinite(out.fit_deg)) out.fit_deg = 3.0 * m.angle_sigma_deg;
  // The end strips' tilts are of one sign on both flanges (both toward the bend): they add.
  out.shape_deg = rss({ta.shape_rad, tb.shape_rad, ta.end_tangent_rad, tb.end_tangent_rad,
                       ta.end_strip_rad + tb.end_strip_rad}) *
                  kRadToDeg;
  out.station_deg = station_angle_deg(st, extent_mm);
  out.angle_deg = rss({out.fit_deg, out.shape_deg, out.station_deg});
  if (!std::isfinite(out.angle_deg)) out.angle_deg = 180.0;  // not fixed at all: says so
  const double window = station_window(m);
  for (const BendStation& s : m.stations) {
    const double w = std::isfinite(window) ? window : 1e9;
    const double fit = std::sqrt(strip_tilt_var(a, m, s.position_mm, w, floor_sigma) +
                                 strip_tilt_var(b, m, s.position_mm, w, floor_sigma)) *
                       kRadToDeg;
    const double u = rss({fit, out.shape_deg, out.station_deg});
    out.station_angle_deg.push_back(std::isfinite(u) ? u : 180.0);
  }
  if (m.zone.fitted) {
    const double sweep = std::abs(m.measured ? m.measured_angle_deg : m.nominal_angle_deg);
    const double fit = std::sqrt(arc_radius_variance(sweep / kRadToDeg, m.zone.inliers,
                                                     std::max(m.zone.rms_mm, floor_sigma)));
    const double scale = extent_mm > 0.0 ? st.calibration_length_mm / extent_mm : 0.0;
    const double thermal = st.expansion_per_k * std::abs(st.temperature_delta_k) / std::sqrt(3.0);
    // The method's own error beyond the arc's noise (the wedge between the tangent lines, the
    // axis' tilt): 0.6 of the zone's rms, as the calibration study shows (docs/uncertainty.md).
    constexpr double kZoneMethodFactor = 0.6;
    out.radius_mm = rss({fit, kZoneMethodFactor * std::max(m.zone.rms_mm, floor_sigma),
                         (scale + thermal) * m.measured_radius_mm});
    if (!std::isfinite(out.radius_mm)) out.radius_mm = m.measured_radius_mm;
  }
  return out;
}

FlangeBudget flange_budget(const FlangeModel& f, double noise, double extent_mm,
                           const UncertaintySettings& st) {
  FlangeBudget out;
  const FlangeShape& shape = f.fit->shape;
  if (!shape.measured) return out;
  const double floor_sigma = st.scanner_sigma_mm;
  const double thermal_mm =
      st.expansion_per_k * std::abs(st.temperature_delta_k) * extent_mm / std::sqrt(3.0);
  // Flatness is the largest inlier's distance from the plane: noise raises it by up to the
  // inlier band (3 robust sigmas), which is its expanded uncertainty (standard: half of it).
  const double band = std::max(shape.inlier_threshold_mm, 3.0 * std::max(noise, floor_sigma));
  out.flatness_mm = rss({band / st.coverage_factor, st.calibration_length_mm});
  if (shape.curled && f.curl.ok && std::isfinite(shape.curl_radius_mm)) {
    // Curvature 1/R = 2A / sqrt(...) ~ 2A near the middle: u(R) = R^2 u(1/R) = 2 R^2 u(A).
    const double sigma_a = std::sqrt(f.curl.a_variance(std::max(f.curl.sigma_mm, floor_sigma)));
    out.curl_radius_mm = 2.0 * sq(shape.curl_radius_mm) * sigma_a;
  }
  // A trim edge: the noise, the calibration and the expansion here; its line's own error (from
  // the point spacing, the spread's even rectangle) and the result frame's move at the edge per
  // edge (attach_uncertainty).
  const double area = 12.0 * std::sqrt(std::max(0.0, f.plane.scatter.determinant()));
  out.spacing_mm = f.plane.points > 0 ? std::sqrt(area / static_cast<double>(f.plane.points)) : 0.0;
  // The line rests on the outermost points, which the noise along the scanner's rays carries
  // out of the sheet as well as along its normal: the largest of an edge's hundred or so
  // readings reaches out by up to about 3 sigma (a ray's noise in plane, sigma sin(incidence),
  // can exceed the plane's residual, sigma cos(incidence), on a tilted view; the study's edges
  // at sigma 0.02 read +0.03-0.04 mm out where the frame was found to 0.01). Uniform over
  // [0, 3 sigma], one-sided and not taken off: the view's incidence is not known here.
  const double sigma = std::max(noise, floor_sigma);
  out.edge_mm = rss({sigma, std::sqrt(3.0) * sigma, st.calibration_length_mm, thermal_mm});
  return out;
}

}  // namespace

std::optional<Error> validate(const UncertaintySettings& st) {
  const auto bad = [](const char* field, double value, const char* rule) {
    return fail(ErrorCode::kInvalidSettings, std::string("settings: uncertainty.") + field + " = " +
                                                 std::to_string(value) + " (" + rule + ")");
  };
  const auto in = [](double v, double lo, double hi) {
    return std::isfinite(v) && v >= lo && v <= hi;
  };
  if (!in(st.scanner_sigma_mm, 0.0, 10.0))
    return bad("scanner_sigma_mm", st.scanner_sigma_mm, "0 to 10");
  if (!in(st.calibration_angle_deg, 0.0, 10.0))
    return bad("calibration_angle_deg", st.calibration_angle_deg, "0 to 10");
  if (!in(st.calibration_length_mm, 0.0, 10.0))
    return bad("calibration_length_mm", st.calibration_length_mm, "0 to 10");
  if (!in(st.temperature_delta_k, -100.0, 100.0))
    return bad("temperature_delta_k", st.temperature_delta_k, "-100 to 100");
  if (!in(st.expansion_per_k, 0.0, 1e-3))
    return bad("expansion_per_k", st.expansion_per_k, "0 to 1e-3");
  if (!in(st.coverage_factor, 1.0, 10.0))
    return bad("coverage_factor", st.coverage_factor, "1 to 10");
  return std::nullopt;
}

UncertaintyResult estimate_uncertainty(const SpringbackResult& sb, double extent_mm,
                                       const UncertaintySettings& st) {
  UncertaintyResult out;
  out.coverage_factor = st.coverage_factor;
  // 1. Each flange's plane (and curl) covariance from its own inlier points.
  std::vector<FlangeModel> flanges(sb.flanges.size());
  for (std::size_t f = 0; f < sb.flanges.size(); ++f) {
    FlangeModel& model = flanges[f];
    model.fit = &sb.flanges[f];
    const FlangeShape& shape = model.fit->shape;
    if (!model.fit->fitted || !shape.measured) continue;
    model.inlier = shape.inlier;
    model.band_mm = shape.inlier_threshold_mm;
    model.plane = plane_covariance(shape.local, model.inlier);
    model.curl = curl_covariance(shape.local, model.inlier);
    model.ok = model.plane.ok;
  }
  // A flange whose shape's points scatter far more than the residual of the local fit that
  // measured its angle, about its plane and about its curl alike (not a bow, which the curl
  // follows), holds what that fit rejected (a solid's end face or a hole's wall within the
  // skin's half thickness, seen from below: 0.2-0.4 mm against 0.008): the plane's own points
  // are then the skin's, as the fit kept them.
  for (FlangeModel& model : flanges)
    if (model.ok && model.curl.ok && model.fit->fit.rms_mm > 0.0 &&
        model.curl.sigma_mm > 3.0 * std::max(model.fit->fit.rms_mm, st.scanner_sigma_mm)) {
      keep_plane_points(model.fit->shape, model);
      model.curl = curl_covariance(model.fit->shape.local, model.inlier);
      // Still far off a plane (the skin is a narrow strip among other faces' points): the
      // local fit's own points and residual tell its tilt.
      model.foreign_points =
          model.plane.sigma_mm > 3.0 * std::max(model.fit->fit.rms_mm, st.scanner_sigma_mm);
    }
  out.noise_mm = std::max(part_noise(flanges), st.scanner_sigma_mm);
  // 2. Each bend's angle, stations and radius; 3. each flange's shape values.
  const auto flange_of = [&](int id) -> const FlangeModel& {
    static const FlangeModel kNone;
    for (const FlangeModel& f : flanges)
      if (f.fit->flange_id == id) return f;
    return kNone;
  };
  for (const BendMeasurement& m : sb.bends)
    out.bends.push_back(
        bend_budget(m, flange_of(m.flange_a), flange_of(m.flange_b), extent_mm, st));
  for (const FlangeModel& f : flanges)
    out.flanges.push_back(flange_budget(f, out.noise_mm, extent_mm, st));
  return out;
}

namespace {

// The edge line's own error (standard, mm): the line over the upper hull of the points of all
// its strips (springback/flange_edge.cpp), band / n taken off, lies short of the edge by an
// exponential share of one point's area over the edge's length, s^2 / L, and its ends by about
// twice that; never more than one spacing.
double edge_line_sigma(const FlangeBudget& f, const EdgeDeviation& e) {
  if (!(e.length_mm > 0.0)) return f.spacing_mm;
  return std::min(f.spacing_mm, 2.0 * f.spacing_mm * f.spacing_mm / e.length_mm);
}

// The result frame's largest move at an edge's strips along `direction` (standard): in plane
// (outward) or across. Each direction its own: a frame that turns a flange about its normal
// moves its edges in plane and not across.
double edge_frame_sigma(const FrameUncertainty* frame, const EdgeDeviation& e,
                        const Vec3& direction) {
  if (!frame || !(direction.norm() > 1e-9)) return 0.0;
  double worst = 0.0;
  for (const Vec3& c : e.cad_edge)
    worst = std::max(worst, frame_point_sigma(*frame, c, direction.normalized()));
  return worst;
}

}  // namespace

void attach_uncertainty(const UncertaintyResult& u, SpringbackResult& sb,
                        const FrameUncertainty* frame) {
  const double k = u.coverage_factor;
  for (std::size_t b = 0; b < sb.bends.size() && b < u.bends.size(); ++b) {
    BendMeasurement& m = sb.bends[b];
    const BendBudget& budget = u.bends[b];
    if (m.zone.fitted) m.radius_uncertainty_mm = k * budget.radius_mm;
    if (!m.measured) continue;
    m.angle_uncertainty_deg = m.springback_uncertainty_deg = k * budget.angle_deg;
    for (std::size_t s = 0; s < m.stations.size() && s < budget.station_angle_deg.size(); ++s)
      m.stations[s].angle_uncertainty_deg = k * budget.station_angle_deg[s];
  }
  for (std::size_t f = 0; f < sb.flanges.size() && f < u.flanges.size(); ++f) {
    FlangeFit& flange = sb.flanges[f];
    if (!flange.shape.measured) continue;
    flange.shape.flatness_uncertainty_mm = k * u.flanges[f].flatness_mm;
    if (flange.shape.curled)
      flange.shape.curl_radius_uncertainty_mm = k * u.flanges[f].curl_radius_mm;
    for (EdgeDeviation& e : flange.trim_edges) {
      if (!e.measured) continue;
      const double own = rss({u.flanges[f].edge_mm, edge_line_sigma(u.flanges[f], e)});
      e.in_plane_uncertainty_mm = k * rss({own, edge_frame_sigma(frame, e, e.outward)});
      e.across_uncertainty_mm =
          k * rss({own, edge_frame_sigma(frame, e, e.direction.cross(e.outward))});
      e.uncertainty_mm = std::max(e.in_plane_uncertainty_mm, e.across_uncertainty_mm);
    }
  }
}

double part_noise_mm(const SpringbackResult& sb) {
  std::vector<double> rms;
  for (const FlangeFit& f : sb.flanges)
    if (f.fitted && f.shape.measured) rms.push_back(f.shape.flatness_rms_mm);
  if (rms.empty()) return 0.0;
  std::sort(rms.begin(), rms.end());
  return rms[(rms.size() - 1) / 2];
}

double neighbour_noise_mm(const std::vector<Vec3>& points, const std::vector<double>& d,
                          double neighbour_mm) {
  if (d.size() != points.size()) return 0.0;
  // At most about kMaxPairs pairs, evenly through the scan: a scale, not a sum.
  constexpr std::size_t kMaxPairs = 20000;
  const std::size_t stride = std::max<std::size_t>(1, points.size() / kMaxPairs);
  std::vector<double> difference;
  difference.reserve(std::min(points.size(), 2 * kMaxPairs));
  const double r2 = neighbour_mm * neighbour_mm;
  for (std::size_t i = 0; i + 1 < points.size(); i += stride)
    if ((points[i + 1] - points[i]).squaredNorm() <= r2)
      difference.push_back(std::abs(d[i + 1] - d[i]));
  if (difference.size() < 100) return 0.0;
  const auto mid = difference.begin() + static_cast<long>(difference.size() / 2);
  std::nth_element(difference.begin(), mid, difference.end());
  return 1.4826 * *mid / std::sqrt(2.0);
}

double p95_outlier_shift_mm(const std::vector<double>& d) {
  if (d.size() < 20) return 0.0;
  constexpr std::size_t kMaxRanked = 100000;  // ranks to about 0.1 %
  const std::size_t every = std::max<std::size_t>(1, d.size() / kMaxRanked);
  std::vector<double> magnitude;
  magnitude.reserve(d.size() / every + 1);
  for (std::size_t i = 0; i < d.size(); i += every) magnitude.push_back(std::abs(d[i]));
  const auto at = [&](double q) {
    const auto rank = static_cast<std::size_t>(q * static_cast<double>(magnitude.size() - 1));
    std::nth_element(magnitude.begin(), magnitude.begin() + static_cast<long>(rank),
                     magnitude.end());
    return magnitude[rank];
  };
  constexpr double kOutlierShare = 0.02;
  const double p95 = at(0.95);
  return std::max(0.0, p95 - at(0.95 - kOutlierShare));
}

void attach_deviation_uncertainty(double noise_mm, double frame_p95_mm, double frame_max_mm,
                                  double outlier_shift_mm, double part_extent_mm,
                                  const UncertaintySettings& st, DeviationStatistics& statistics) {
  if (statistics.points == 0) return;
  const double k = st.coverage_factor;
  const double thermal =
      st.expansion_per_k * std::abs(st.temperature_delta_k) * part_extent_mm / std::sqrt(3.0);
  const double noise = std::max(noise_mm, st.scanner_sigma_mm);
  // The noise raises the p95 of |d| by 0 (a surface whose deviation spreads far wider than the
  // noise) up to 1.96 sigma (a surface on its CAD: the p95 is the noise's), 2.15 sigma with 2 %
  // outliers above it: uniform over [0, 2.2 sigma]. One point (the largest |d|) carries its
  // noise and, as an extreme, up to ~3 sigmas of it.
  constexpr double kP95NoiseFactor = 2.2 / 1.7320508075688772;
  const double station = rss({st.calibration_length_mm, thermal});
  // Outliers above the p95 (up to 2 % of the points) raise its rank among the surface's own
  // distances by their share: uniform over [0, the shift].
  statistics.p95_uncertainty_mm =
      k * rss({kP95NoiseFactor * noise, outlier_shift_mm / std::sqrt(3.0), frame_p95_mm, station});
  statistics.max_uncertainty_mm = k * rss({1.5 * noise, frame_max_mm, station});
}

}  // namespace springscan::analysis
