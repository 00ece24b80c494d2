#include "analysis/springback/flange_shape.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <vector>

namespace springscan::analysis {
namespace {

using Vec5 = Eigen::Matrix<double, 5, 1>;
using Mat5 = Eigen::Matrix<double, 5, 5>;
constexpr double kRadToDeg = 180.0 / std::numbers::pi;
constexpr int kRobustRounds = 3;  // solves: all points, then inliers twice

// Regressors of h for the model A (s^2 + h^2) + B s + C + E t + G s t, q = (s, t, h).
Vec5 regressors(const Vec3& q) {
  Vec5 x;
  x << q.x() * q.x() + q.z() * q.z(), q.x(), 1.0, q.y(), q.x() * q.y();
  return x;
}

double model_h(const FlangeSurface& f, const Vec3& q) {
  return f.A * (q.x() * q.x() + q.z() * q.z()) + (f.B + f.G * q.y()) * q.x() + f.C + f.E * q.y();
}

struct Solved {
  FlangeSurface surface;
  double sigma_A = 0.0;  // standard error of A
  bool ok = false;
};

// Least squares over the points whose |residual| from `previous` is within `threshold` (all
// points when threshold is infinite); `with_curl` false holds A at 0.
Solved solve(const std::vector<Vec3>& q, const FlangeSurface& previous, double threshold,
             bool with_curl) {
  Mat5 normal = Mat5::Zero();
  Vec5 rhs = Vec5::Zero();
  double sum_h2 = 0.0;
  std::size_t n = 0;
  for (const Vec3& p : q) {
    if (!(std::abs(p.z() - model_h(previous, p)) <= threshold)) continue;
    const Vec5 x = regressors(p);
    normal.noalias() += x * x.transpose();
    rhs += x * p.z();
    sum_h2 += p.z() * p.z();
    ++n;
  }
  if (!with_curl) {
    normal.row(0).setZero();
    normal.col(0).setZero();
    normal(0, 0) = 1.0;
    rhs(0) = 0.0;
  }
  Solved out;
  if (n < 6) return out;
  const Eigen::LDLT<Mat5> ldlt(normal);
  if (ldlt.info() != Eigen::Success || !(ldlt.rcond() > 1e-14)) return out;
  const Vec5 beta = ldlt.solve(rhs);
  if (!beta.allFinite()) return out;
  out.surface = {beta(0), beta(1), beta(2), beta(3), beta(4)};
  // Residual variance from the normal equations: sum h^2 - beta' rhs.
  const double dof = static_cast<double>(n) - (with_curl ? 5.0 : 4.0);
  const double variance = std::max(0.0, sum_h2 - beta.dot(rhs)) / std::max(1.0, dof);
  if (with_curl) out.sigma_A = std::sqrt(variance * ldlt.solve(Vec5::Unit(0))(0));
  out.ok = true;
  return out;
}

// 1.4826 MAD of the residuals of the points within `threshold` of the surface.
double robust_sigma(const std::vector<Vec3>& q, const FlangeSurface& f) {
  std::vector<double> r;
  r.reserve(q.size());
  for (const Vec3& p : q) r.push_back(std::abs(p.z() - model_h(f, p)));
  const auto mid = r.begin() + static_cast<std::ptrdiff_t>(r.size() / 2);
  std::nth_element(r.begin(), mid, r.end());
  return 1.4826 * *mid;
}

// Flatness: distances of the inliers from their least-squares plane h = b s + c + e t.
void flatness(const std::vector<Vec3>& q, const FlangeShape& shape, FlangeShape& out) {
  Eigen::Matrix3d normal = Eigen::Matrix3d::Zero();
  Eigen::Vector3d rhs = Eigen::Vector3d::Zero();
  for (std::size_t i = 0; i < q.size(); ++i) {
    if (!shape.inlier[i]) continue;
    const Vec3& p = q[i];
    const Eigen::Vector3d x(p.x(), 1.0, p.y());
    normal += x * x.transpose();
    rhs += x * p.z();
  }
  const Eigen::Vector3d plane = normal.ldlt().solve(rhs);
  const double scale = 1.0 / std::sqrt(1.0 + plane(0) * plane(0) + plane(2) * plane(2));
  double sum2 = 0.0, worst = 0.0;
  std::size_t n = 0;
  for (std::size_t i = 0; i < q.size(); ++i) {
    if (!shape.inlier[i]) continue;
    const Vec3& p = q[i];
    const double d = std::abs(p.z() - plane(0) * p.x() - plane(1) - plane(2) * p.y()) * scale;
    sum2 += d * d;
    worst = std::max(worst, d);
    ++n;
  }
  out.inliers = n;
  out.flatness_rms_mm = n > 0 ? std::sqrt(sum2 / static_cast<double>(n)) : 0.0;
  out.flatness_max_mm = worst;
}

// Robust fit: all points first, then twice the points within outlier_sigmas robust sigmas.
bool robust_fit(const std::vector<Vec3>& q, const FlangeShapeSettings& st, FlangeShape& shape,
                double& sigma_A) {
  double threshold = std::numeric_limits<double>::infinity();
  FlangeSurface surface;
  for (int round = 0; round < kRobustRounds; ++round) {
    const Solved s = solve(q, surface, threshold, true);
    if (!s.ok) return false;
    surface = s.surface;
    sigma_A = s.sigma_A;
    threshold = std::max(st.outlier_sigmas * robust_sigma(q, surface), 1e-9);
  }
  shape.surface = surface;
  shape.inlier_threshold_mm = threshold;
  return true;
}

// The flags of the points within the inlier threshold of the surface.
std::vector<std::uint8_t> inlier_flags(const std::vector<Vec3>& q, const FlangeShape& shape) {
  std::vector<std::uint8_t> flags(q.size());
  for (std::size_t i = 0; i < q.size(); ++i)
    flags[i] = std::abs(q[i].z() - model_h(shape.surface, q[i])) <= shape.inlier_threshold_mm;
  return flags;
}

}  // namespace

FlangeFrame flange_frame(const PointCloud& cloud, std::span<const std::uint32_t> points,
                         const Vec3& normal, const Vec3& along) {
  FlangeFrame f;
  f.n = normal.normalized();
  f.d = (along - along.dot(f.n) * f.n).normalized();
  f.u = f.d.cross(f.n);
  Vec3 sum = Vec3::Zero();
  for (std::uint32_t i : points) sum += cloud.points[i];
  if (!points.empty()) f.origin = sum / static_cast<double>(points.size());
  return f;
}

FlangeShape fit_flange_shape(const PointCloud& cloud, std::span<const std::uint32_t> points,
                             const FlangeFrame& frame, const FlangeShapeSettings& st,
                             double plane_rms_mm) {
  FlangeShape shape;
  shape.frame = frame;
  if (points.size() < static_cast<std::size_t>(std::max(st.min_points, 6))) return shape;
  std::vector<Vec3> q;
  q.reserve(points.size());
  double t_min = std::numeric_limits<double>::infinity(), t_max = -t_min;
  for (std::uint32_t i : points) {
    q.push_back(frame.local(cloud.points[i]));
    t_min = std::min(t_min, q.back().y());
    t_max = std::max(t_max, q.back().y());
  }
  double sigma_A = 0.0;
  if (!robust_fit(q, st, shape, sigma_A)) return shape;
  // Curvature of the middle section (t = 0) and how far such a curl bows the points' width.
  const FlangeSurface& f = shape.surface;
  const double k = 2.0 * f.A / std::sqrt(std::max(1e-12, f.B * f.B + 1.0 - 4.0 * f.A * f.C));
  // The width the curl bows over is the inliers': a few stray points beyond the flange's
  // edge (another face's, nearest to this flange's samples) made a 15 mm tab 40 mm wide and
  // its noise-level curvature a 0.1 mm bow.
  double in_min = std::numeric_limits<double>::infinity(), in_max = -in_min, sum2 = 0.0;
  std::size_t inliers = 0;
  for (const Vec3& p : q) {
    const double r = p.z() - model_h(f, p);
    if (!(std::abs(r) <= shape.inlier_threshold_mm)) continue;
    in_min = std::min(in_min, p.x()), in_max = std::max(in_max, p.x());
    sum2 += r * r;
    ++inliers;
  }
  const double width = in_max > in_min ? in_max - in_min : 0.0;
  const double curl_rms = inliers > 0 ? std::sqrt(sum2 / static_cast<double>(inliers)) : 0.0;
  shape.curled = std::abs(f.A) > st.curl_significance * sigma_A &&
                 std::abs(k) * width * width / 8.0 >= st.min_curl_sagitta_mm &&
                 curl_rms <= plane_rms_mm;
  if (shape.curled) {
    shape.curl_radius_mm = 1.0 / k;
  } else {  // flat: the plane-and-twist model on the same inliers
    const Solved flat = solve(q, shape.surface, shape.inlier_threshold_mm, false);
    if (!flat.ok) return shape;
    shape.surface = flat.surface;
  }
  // A section turns by G / (1 + B^2) per mm along t; right-handed about d is -that (u = d x n
  // tilts towards +h as the normal turns about d the other way).
  const double B = shape.surface.B;
  shape.twist_deg_per_100mm = -shape.surface.G / (1.0 + B * B) * kRadToDeg * 100.0;
  shape.twist_measured = t_max - t_min >= st.min_twist_length_mm;
  shape.inlier = inlier_flags(q, shape);
  flatness(q, shape, shape);
  shape.local = std::move(q);
  shape.measured = true;
  return shape;
}

Vec3 end_normal(const FlangeFrame& frame, const FlangeSurface& f, const Vec3& near) {
  const Vec3 c = frame.local(near);
  const double b = f.B + f.G * c.y(), k0 = f.C + f.E * c.y();
  // Gradient of A (s^2 + h^2) + b s + k0 - h at the section's point closest to c; for a plane
  // it is the same everywhere, for a circle that point lies on the ray from its centre to c.
  double s = c.x(), h = c.z();
  if (f.A != 0.0) {
    const Eigen::Vector2d centre(-b / (2.0 * f.A), 1.0 / (2.0 * f.A));
    const double radius =
        std::sqrt(std::max(0.0, b * b + 1.0 - 4.0 * f.A * k0)) / (2.0 * std::abs(f.A));
    const Eigen::Vector2d ray = Eigen::Vector2d(c.x(), c.z()) - centre;
    const Eigen::Vector2d foot = centre + radius * ray.normalized();
    s = foot.x();
    h = foot.y();
  }
  const double fs = 2.0 * f.A * s + b, fh = 2.0 * f.A * h - 1.0, ft = f.E + f.G * s;
  // The normal of f = 0 is its gradient; -gradient points along +n (fh is near -1).
  return (-fs * frame.u - ft * frame.d - fh * frame.n).normalized();
}

StripFit::StripFit(const FlangeSurface& surface, double t_centre)
    : A_(surface.A), t_centre_(t_centre) {}

void StripFit::add(const Vec3& q) {
  const Eigen::Vector3d x(q.x(), 1.0, q.y() - t_centre_);
  normal_ += x * x.transpose();
  rhs_ += x * (q.z() - A_ * (q.x() * q.x() + q.z() * q.z()));
  ++count_;
}

bool StripFit::solve(FlangeSurface& out) const {
  if (count_ < 6) return false;
  const Eigen::LDLT<Eigen::Matrix3d> ldlt(normal_);
  if (ldlt.info() != Eigen::Success || !(ldlt.rcond() > 1e-12)) return false;
  const Eigen::Vector3d beta = ldlt.solve(rhs_);
  if (!beta.allFinite()) return false;
  // Back to the flange's t origin: C + E (t - t_centre) = (C - E t_centre) + E t.
  out = {A_, beta(0), beta(1) - beta(2) * t_centre_, beta(2), 0.0};
  return true;
}

}  // namespace springscan::analysis
