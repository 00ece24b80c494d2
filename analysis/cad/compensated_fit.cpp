// The refits of moved faces and edges (compensated_internal.hpp): planes and cylinders that stay
// canonical, least-squares cubic B-splines in the old parameters otherwise.
#include <BRep_Tool.hxx>
#include <Eigen/Eigenvalues>
#include <Geom2d_BSplineCurve.hxx>
#include <GeomAdaptor_Surface.hxx>
#include <Geom_BSplineSurface.hxx>
#include <Geom_CylindricalSurface.hxx>
#include <Geom_Plane.hxx>
#include <TColStd_Array1OfInteger.hxx>
#include <TColStd_Array1OfReal.hxx>
#include <TColgp_Array1OfPnt.hxx>
#include <TColgp_Array1OfPnt2d.hxx>
#include <TColgp_Array2OfPnt.hxx>
#include <algorithm>
#include <cmath>
#include <numbers>

#include "analysis/cad/compensated_internal.hpp"
#include "analysis/cad/internal.hpp"

namespace springscan::analysis::compensated {
namespace {

constexpr int kDegree = 3;
constexpr int kMaxSpans = 32;  // per direction: 35 x 35 poles at most

Vec3 v3(const gp_XYZ& p) { return {p.X(), p.Y(), p.Z()}; }
gp_Pnt pnt(const Vec3& p) { return {p.x(), p.y(), p.z()}; }
gp_Dir dir(const Vec3& d) { return {d.x(), d.y(), d.z()}; }
// A sample's weight in a plane or cylinder fit: 1 / allowance^2 (the field's certainty there).
double weight(const FaceSample& s) {
  return 1.0 / std::max(s.allowance_mm * s.allowance_mm, 1e-12);
}

// A clamped uniform cubic knot vector over [a, b] with `spans` spans.
struct Knots {
  double a = 0.0, b = 1.0;
  int spans = 1;
  int poles() const { return spans + kDegree; }
  // The span of x and the kDegree + 1 non-zero basis values there (The NURBS Book, A2.2).
  int basis(double x, double* values) const {
    const double h = (b - a) / spans;
    const int span = std::clamp(static_cast<int>(std::floor((x - a) / h)), 0, spans - 1);
    auto knot = [&](int i) { return a + std::clamp(i, 0, spans) * h; };  // interior index
    double left[kDegree + 1], right[kDegree + 1];
    values[0] = 1.0;
    for (int j = 1; j <= kDegree; ++j) {
      left[j] = x - knot(span + 1 - j);
      right[j] = knot(span + j) - x;
      double saved = 0.0;
      for (int r = 0; r < j; ++r) {
        const double denominator = right[r + 1] + left[j - r];
        const double t = denominator != 0.0 ? values[r] / denominator : 0.0;
        values[r] = saved + right[r + 1] * t;
        saved = left[j - r] * t;
      }
      values[j] = saved;
    }
    return span;  // values[k] belongs to pole span + k
  }
  void fill(TColStd_Array1OfReal& knots, TColStd_Array1OfInteger& mults) const {
    for (int i = 0; i <= spans; ++i) {
      knots.SetValue(i + 1, a + (b - a) * i / spans);
      mults.SetValue(i + 1, i == 0 || i == spans ? kDegree + 1 : 1);
    }
  }
};

// Second differences of a pole sequence (stride `step`) into the smoothing term: it keeps the
// system regular where no sample lies and is zero on affine pole grids (planes stay exact).
void add_smoothing(Eigen::MatrixXd& normal, int first, int step, int count, double weight) {
  for (int k = 0; k + 2 < count; ++k) {
    const int i[3] = {first + k * step, first + (k + 1) * step, first + (k + 2) * step};
    const double c[3] = {1.0, -2.0, 1.0};
    for (int r = 0; r < 3; ++r)
      for (int s = 0; s < 3; ++s) normal(i[r], i[s]) += weight * c[r] * c[s];
  }
}

// Least squares for the poles of a tensor B-spline through (uv, point) samples.
Eigen::MatrixXd solve_surface(const Knots& ku, const Knots& kv,
                              const std::vector<FaceSample>& samples) {
  const int nu = ku.poles(), nv = kv.poles(), n = nu * nv;
  Eigen::MatrixXd normal = Eigen::MatrixXd::Zero(n, n), rhs = Eigen::MatrixXd::Zero(n, 3);
  double bu[kDegree + 1], bv[kDegree + 1];
  for (const FaceSample& s : samples) {
    const int su = ku.basis(s.uv.x(), bu), sv = kv.basis(s.uv.y(), bv);
    int index[(kDegree + 1) * (kDegree + 1)];
    double value[(kDegree + 1) * (kDegree + 1)];
    int m = 0;
    for (int i = 0; i <= kDegree; ++i)
      for (int j = 0; j <= kDegree; ++j, ++m) {
        index[m] = (su + i) * nv + (sv + j);
        value[m] = bu[i] * bv[j];
      }
    for (int r = 0; r < m; ++r) {
      rhs.row(index[r]) += value[r] * s.moved.transpose();
      for (int c = 0; c < m; ++c) normal(index[r], index[c]) += value[r] * value[c];
    }
  }
  const double weight = 1e-6 * std::max(1.0, normal.trace() / n);
  for (int i = 0; i < nu; ++i) add_smoothing(normal, i * nv, 1, nv, weight);
  for (int j = 0; j < nv; ++j) add_smoothing(normal, j, nv, nu, weight);
  return normal.ldlt().solve(rhs);
}

Handle(Geom_BSplineSurface) bspline_surface(const TopoDS_Face&, const std::vector<FaceSample>& s,
                                            const Eigen::Vector4d& box, int spans) {
  const Knots ku{box[0], box[1], spans}, kv{box[2], box[3], spans};
  const Eigen::MatrixXd poles = solve_surface(ku, kv, s);
  TColgp_Array2OfPnt array(1, ku.poles(), 1, kv.poles());
  for (int i = 0; i < ku.poles(); ++i)
    for (int j = 0; j < kv.poles(); ++j)
      array.SetValue(i + 1, j + 1, pnt(poles.row(i * kv.poles() + j).transpose()));
  TColStd_Array1OfReal uk(1, spans + 1), vk(1, spans + 1);
  TColStd_Array1OfInteger um(1, spans + 1), vm(1, spans + 1);
  ku.fill(uk, um);
  kv.fill(vk, vm);
  return new Geom_BSplineSurface(array, uk, vk, um, vm, kDegree, kDegree);
}

// The plane through the samples, weighted by 1 / allowance^2 (least squares), when every sample
// lies within its allowance.
bool fit_plane(const gp_Ax3& old, const std::vector<FaceSample>& s,
               const CompensatedShapeSettings& settings, FaceFit& fit) {
  Vec3 mean = Vec3::Zero();
  double weight_sum = 0.0;
  for (const auto& p : s) {
    mean += weight(p) * p.moved;
    weight_sum += weight(p);
  }
  mean /= weight_sum;
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
  for (const auto& p : s) covariance += weight(p) * (p.moved - mean) * (p.moved - mean).transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(covariance);
  const Vec3 normal = eigen.eigenvectors().col(0);
  std::vector<double> residual;
  for (const auto& p : s) residual.push_back(std::abs(normal.dot(p.moved - mean)));
  fit.canonical_deviation_mm = *std::max_element(residual.begin(), residual.end());
  if (!within_allowance(s, residual, settings)) return false;
  const double deviation = fit.canonical_deviation_mm;
  fit = plane_surface(old, mean, normal);
  fit.canonical_deviation_mm = fit.max_deviation_mm = deviation;
  return true;
}

// The cylinder through the samples: the axis along the moved grid columns (constant u), the
// circle by Kasa's algebraic fit across it; accepted when every sample lies within `tolerance`.
bool fit_cylinder(const gp_Ax3& old, const std::vector<FaceSample>& s,
                  const CompensatedShapeSettings& settings, FaceFit& fit) {
  std::vector<std::pair<int, const FaceSample*>> low, high;  // per column: lowest/highest row
  int columns = 0;
  for (const auto& p : s) columns = std::max(columns, p.column + 1);
  low.assign(static_cast<std::size_t>(columns), {1 << 30, nullptr});
  high.assign(static_cast<std::size_t>(columns), {-1, nullptr});
  for (const auto& p : s) {
    if (p.column < 0) continue;
    auto& lo = low[static_cast<std::size_t>(p.column)];
    auto& hi = high[static_cast<std::size_t>(p.column)];
    if (p.row < lo.first) lo = {p.row, &p};
    if (p.row > hi.first) hi = {p.row, &p};
  }
  Vec3 axis = Vec3::Zero();
  for (int c = 0; c < columns; ++c)
    if (low[c].second && high[c].first > low[c].first)
      axis += (high[c].second->moved - low[c].second->moved).normalized();
  if (!(axis.norm() > 0.5)) return false;
  axis.normalize();
  const Vec3 e1 = axis.unitOrthogonal(), e2 = axis.cross(e1);
  Eigen::MatrixXd a(static_cast<Eigen::Index>(s.size()), 3);
  Eigen::VectorXd b(static_cast<Eigen::Index>(s.size()));
  for (std::size_t i = 0; i < s.size(); ++i) {
    const double x = s[i].moved.dot(e1), y = s[i].moved.dot(e2), w = std::sqrt(weight(s[i]));
    a.row(static_cast<Eigen::Index>(i)) << w * x, w * y, w;
    b[static_cast<Eigen::Index>(i)] = -w * (x * x + y * y);
  }
  const Eigen::Vector3d c = a.colPivHouseholderQr().solve(b);
  const double cx = -c[0] / 2.0, cy = -c[1] / 2.0, r2 = cx * cx + cy * cy - c[2];
  if (!(r2 > 0.0)) return false;
  const double radius = std::sqrt(r2);
  const Vec3 center = cx * e1 + cy * e2;
  double worst = 0.0;
  std::vector<double> residual;
  Vec3 mid = Vec3::Zero();
  for (const auto& p : s) {
    const Vec3 w = p.moved - center;
    residual.push_back(std::abs((w - w.dot(axis) * axis).norm() - radius));
    worst = std::max(worst, residual.back());
    mid += p.moved;
  }
  fit.canonical_deviation_mm = worst;
  if (!within_allowance(s, residual, settings)) return false;
  mid /= static_cast<double>(s.size());
  Vec3 x = mid - center;
  x = (x - x.dot(axis) * axis).normalized();  // u = 0 mid-face: a bend never wraps
  gp_Ax3 frame(pnt(center), dir(axis), dir(x));
  if (!old.Direct()) frame.YReverse();  // Pu x Pv keeps pointing away from (towards) the axis
  fit.kind = "cylinder";
  fit.origin = center;
  fit.z = axis;
  fit.x = x;
  fit.y = v3(frame.YDirection().XYZ());
  fit.radius = radius;
  fit.max_deviation_mm = worst;
  fit.surface = new Geom_CylindricalSurface(frame, radius);
  return true;
}

}  // namespace

bool within_allowance(const std::vector<FaceSample>& samples, const std::vector<double>& residual,
                      const CompensatedShapeSettings& settings) {
  std::size_t within = 0;
  for (std::size_t i = 0; i < samples.size(); ++i) {
    if (!(residual[i] <= settings.max_canonical_deviation_mm)) return false;
    within += residual[i] <= samples[i].allowance_mm ? 1 : 0;
  }
  return static_cast<double>(within) >=
         settings.canonical_share * static_cast<double>(samples.size());
}

FaceFit plane_surface(const gp_Ax3& old, const Vec3& point, Vec3 normal) {
  // The surface normal Pu x Pv keeps its side, so the face keeps its orientation.
  const Vec3 old_normal = v3(old.XDirection().XYZ()).cross(v3(old.YDirection().XYZ()));
  if (normal.dot(old_normal) < 0.0) normal = -normal;
  Vec3 x = v3(old.XDirection().XYZ());
  x = (x - x.dot(normal) * normal).normalized();
  FaceFit fit;
  fit.kind = "plane";
  fit.same_parameters = false;
  fit.origin = point;
  fit.z = normal;
  fit.x = x;
  fit.y = normal.cross(x);
  fit.surface = new Geom_Plane(gp_Ax3(pnt(point), dir(normal), dir(x)));
  return fit;
}

Eigen::Vector2d FaceFit::uv_of(const Vec3& moved) const {
  const Vec3 w = moved - origin;
  if (kind == "plane") return {w.dot(x), w.dot(y)};
  return {std::atan2(w.dot(y), w.dot(x)), w.dot(z)};
}

FaceFit fit_face(const TopoDS_Face& face, const std::vector<FaceSample>& samples,
                 const Eigen::Vector4d& uv_box, bool may_be_canonical,
                 const CompensatedShapeSettings& settings) {
  FaceFit fit;
  const GeomAdaptor_Surface old(BRep_Tool::Surface(face));
  if (may_be_canonical && old.GetType() == GeomAbs_Plane &&
      fit_plane(old.Plane().Position(), samples, settings, fit)) {
    fit.same_parameters = false;
    return fit;
  }
  if (may_be_canonical && old.GetType() == GeomAbs_Cylinder &&
      fit_cylinder(old.Cylinder().Position(), samples, settings, fit)) {
    fit.same_parameters = false;
    return fit;
  }
  fit.kind = "bspline";
  // Finer spans until the refit follows the samples (a field that turns at a bend crosses a
  // sheet's end face: a kink no coarse spline follows).
  for (int spans = std::max(1, settings.face_spans);; spans *= 2) {
    fit.surface = bspline_surface(face, samples, uv_box, spans);
    fit.max_deviation_mm = 0.0;
    for (const auto& s : samples) {
      const Vec3 on = v3(fit.surface->Value(s.uv.x(), s.uv.y()).XYZ());
      fit.max_deviation_mm = std::max(fit.max_deviation_mm, (on - s.moved).norm());
    }
    if (fit.max_deviation_mm <= settings.bspline_tolerance_mm || spans >= kMaxSpans) return fit;
  }
}

namespace {

template <int N>
Eigen::MatrixXd solve_curve(const Knots& k, const std::vector<double>& t,
                            const std::vector<Eigen::Matrix<double, N, 1>>& points) {
  const int n = k.poles();
  Eigen::MatrixXd normal = Eigen::MatrixXd::Zero(n, n), rhs = Eigen::MatrixXd::Zero(n, N);
  double b[kDegree + 1];
  for (std::size_t i = 0; i < t.size(); ++i) {
    const int span = k.basis(t[i], b);
    for (int r = 0; r <= kDegree; ++r) {
      rhs.row(span + r) += b[r] * points[i].transpose();
      for (int c = 0; c <= kDegree; ++c) normal(span + r, span + c) += b[r] * b[c];
    }
  }
  add_smoothing(normal, 0, 1, n, 1e-9 * std::max(1.0, normal.trace() / n));
  return normal.ldlt().solve(rhs);
}

Knots curve_knots(const std::vector<double>& t) {
  // A few samples per span: cubic spans, at most 8 (edges are short and smooth).
  const int spans = std::clamp(static_cast<int>(t.size()) / 5, 1, 8);
  return Knots{t.front(), t.back(), spans};
}

}  // namespace

Handle(Geom_BSplineCurve) fit_curve(const std::vector<double>& t, const std::vector<Vec3>& points,
                                    double& max_deviation_mm) {
  const Knots k = curve_knots(t);
  const Eigen::MatrixXd poles = solve_curve<3>(k, t, points);
  TColgp_Array1OfPnt array(1, k.poles());
  for (int i = 0; i < k.poles(); ++i) array.SetValue(i + 1, pnt(poles.row(i).transpose()));
  TColStd_Array1OfReal knots(1, k.spans + 1);
  TColStd_Array1OfInteger mults(1, k.spans + 1);
  k.fill(knots, mults);
  Handle(Geom_BSplineCurve) curve = new Geom_BSplineCurve(array, knots, mults, kDegree);
  max_deviation_mm = 0.0;
  for (std::size_t i = 0; i < t.size(); ++i)
    max_deviation_mm =
        std::max(max_deviation_mm, (v3(curve->Value(t[i]).XYZ()) - points[i]).norm());
  return curve;
}

Handle(Geom2d_Curve)
    fit_curve_2d(const std::vector<double>& t, const std::vector<Eigen::Vector2d>& uv) {
  const Knots k = curve_knots(t);
  const Eigen::MatrixXd poles = solve_curve<2>(k, t, uv);
  TColgp_Array1OfPnt2d array(1, k.poles());
  for (int i = 0; i < k.poles(); ++i) array.SetValue(i + 1, gp_Pnt2d(poles(i, 0), poles(i, 1)));
  TColStd_Array1OfReal knots(1, k.spans + 1);
  TColStd_Array1OfInteger mults(1, k.spans + 1);
  k.fill(knots, mults);
  return new Geom2d_BSplineCurve(array, knots, mults, kDegree);
}

}  // namespace springscan::analysis::compensated
