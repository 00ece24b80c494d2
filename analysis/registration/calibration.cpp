#include "analysis/registration/calibration.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <optional>

#include "analysis/core/parallel.hpp"
#include "analysis/registration/facing.hpp"

namespace springscan::analysis {
namespace {

constexpr double kRadToDeg = 180.0 / std::numbers::pi;
constexpr std::size_t kMinPoints = 100;

std::vector<Vec3> strided(const std::vector<Vec3>& points, std::size_t max_points) {
  if (points.size() <= max_points || max_points == 0) return points;
  std::vector<Vec3> out;
  out.reserve(max_points);
  const double step = static_cast<double>(points.size()) / static_cast<double>(max_points);
  for (std::size_t i = 0; i < max_points; ++i)
    out.push_back(points[static_cast<std::size_t>(static_cast<double>(i) * step)]);
  return out;
}

/// The encoder scale about the raw points' centre along the motion axis: centred, the scale and
/// the translation along that axis stay nearly independent, so alternating them converges fast.
struct MotionScale {
  int axis = 2;
  double centre = 0.0;
  double k = 1.0;
  Vec3 apply(const Vec3& p) const {
    Vec3 q = p;
    q[axis] = centre + k * (p[axis] - centre);
    return q;
  }
};

std::vector<Vec3> scaled(const std::vector<Vec3>& points, const MotionScale& s) {
  std::vector<Vec3> out;
  out.reserve(points.size());
  for (const Vec3& p : points) out.push_back(s.apply(p));
  return out;
}

/// The residuals at the final pose and the point-to-plane normal matrix of the inliers.
struct Evaluation {
  std::vector<double> residual;  // signed, along the surface normal
  std::vector<Vec3> normal;
  std::vector<Vec3> station;  // T * scaled point
  std::vector<char> inlier;
  std::size_t inliers = 0;
  double rms = 0.0, p95 = 0.0;
  Vec3 centre = Vec3::Zero();
};

Evaluation evaluate(const std::vector<Vec3>& points, const Transform& T,
                    const SurfaceDistance& exact, const HeadCalibrationSettings& settings) {
  Evaluation e;
  const std::size_t n = points.size();
  e.residual.resize(n);
  e.normal.resize(n);
  e.station.resize(n);
  parallel_blocks(n, settings.threads, [&](std::size_t, std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      e.station[i] = T * points[i];
      const SurfaceHit hit = exact.closest(e.station[i]);
      e.normal[i] = hit.normal;
      e.residual[i] = hit.normal.dot(e.station[i] - hit.foot);
    }
  });
  // Outliers by a robust sigma (1.4826 x the median |residual|, the MAD of a normal).
  std::vector<double> magnitude;
  magnitude.reserve(n);
  for (const double r : e.residual) magnitude.push_back(std::abs(r));
  std::vector<double> sorted = magnitude;
  std::nth_element(sorted.begin(), sorted.begin() + static_cast<long>(n / 2), sorted.end());
  const double limit = settings.outlier_sigma_factor * 1.4826 * sorted[n / 2];
  e.inlier.assign(n, 0);
  std::vector<double> kept;
  double sum2 = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    if (!std::isfinite(e.residual[i]) || magnitude[i] > limit) continue;
    e.inlier[i] = 1;
    kept.push_back(magnitude[i]);
    sum2 += e.residual[i] * e.residual[i];
    e.centre += e.station[i];
  }
  e.inliers = kept.size();
  if (e.inliers == 0) return e;
  e.centre /= static_cast<double>(e.inliers);
  e.rms = std::sqrt(sum2 / static_cast<double>(e.inliers));
  const auto at95 = static_cast<long>(std::floor(0.95 * static_cast<double>(kept.size() - 1)));
  std::nth_element(kept.begin(), kept.begin() + at95, kept.end());
  e.p95 = kept[static_cast<std::size_t>(at95)];
  return e;
}

/// Normal matrix and gradient over the inliers, parameters (rx, ry, rz about the centre,
/// tx, ty, tz, and the motion scale when fitted): J_i = [(s_i - c) x n_i, n_i, n_i . R e_m
/// (p_m - centre_m)] for the point-to-plane residual r_i (Chen and Medioni 1992).
void normal_equations(const Evaluation& e, const std::vector<Vec3>& raw, const Transform& T,
                      const MotionScale* scale, Eigen::MatrixXd& H, Eigen::VectorXd& g) {
  const int m = scale ? 7 : 6;
  H = Eigen::MatrixXd::Zero(m, m);
  g = Eigen::VectorXd::Zero(m);
  Eigen::VectorXd J(m);
  const Vec3 motion = scale ? Vec3(T.linear().col(scale->axis)) : Vec3::Zero();
  for (std::size_t i = 0; i < raw.size(); ++i) {
    if (!e.inlier[i]) continue;
    J.head<3>() = (e.station[i] - e.centre).cross(e.normal[i]);
    J.segment<3>(3) = e.normal[i];
    if (scale) J[6] = e.normal[i].dot(motion) * (raw[i][scale->axis] - scale->centre);
    H.noalias() += J * J.transpose();
    g.noalias() += J * e.residual[i];
  }
}

/// The rms distance of the inliers from their centroid: the lever arm that makes a rotation's
/// information comparable with a translation's.
double rms_radius(const Evaluation& e) {
  double radius2 = 0.0;
  for (std::size_t i = 0; i < e.station.size(); ++i)
    if (e.inlier[i]) radius2 += (e.station[i] - e.centre).squaredNorm();
  return std::sqrt(radius2 / static_cast<double>(std::max<std::size_t>(1, e.inliers)));
}

Expected<Transform> initial_pose(const std::vector<Vec3>& points, const PartModel& artefact,
                                 const HeadCalibrationSettings& settings) {
  if (settings.use_initial_pose) return settings.initial_pose;
  const KdTree tree(artefact.samples.points);
  GlobalFitSettings global = settings.initial;
  global.exact_iterations = 0;  // the calibration's own fit follows, on the exact surface
  global.icp.threads = settings.threads;
  auto fit = global_fit(points, tree, artefact.samples.normals, global);
  if (!fit) return fit.error().prepend("head calibration: first pose: ");
  return fit->T_cad_scan;
}

std::optional<Error> check_input(const std::vector<Vec3>& head_points, const PartModel& artefact,
                                 const HeadCalibrationSettings& settings) {
  if (head_points.size() < kMinPoints)
    return fail("head calibration: " + std::to_string(head_points.size()) + " points; at least " +
                std::to_string(kMinPoints) + " needed");
  for (const Vec3& p : head_points)
    if (!p.allFinite()) return fail("head calibration: the scan has non-finite points");
  if (!artefact.distance || artefact.samples.empty())
    return fail("head calibration: the artefact model needs its exact CAD distance and samples");
  if (settings.motion_axis < 0 || settings.motion_axis > 2)
    return fail(ErrorCode::kInvalidSettings,
                "head calibration: motion_axis = " + std::to_string(settings.motion_axis) +
                    ": allowed 0, 1 or 2");
  return validate(settings.icp, "head calibration: icp.");
}

/// The rigid fit on the exact surface, and with the scale, after each fit one Gauss-Newton step
/// of all seven parameters at the fitted pose whose scale part is kept (it allows for the scale's
/// correlation with the pose); the pose is then fitted again. Updates T, scale, out.icp.
std::optional<Error> fit_rounds(const std::vector<Vec3>& raw, const PartModel& artefact,
                                const HeadCalibrationSettings& settings, Transform& T,
                                MotionScale& scale, HeadCalibration& out) {
  IcpSettings icp_settings = settings.icp;
  icp_settings.threads = settings.threads;
  // Points only, no distance limit: outliers are the robust kernel's (settings.icp).
  static const std::vector<Vec3> kNoNormals;
  const IcpPairSearch pairs = exact_surface_pairs(*artefact.distance, kNoNormals, 0.0);
  Eigen::MatrixXd H;
  Eigen::VectorXd g;
  for (;;) {
    auto fit = icp(scaled(raw, scale), pairs, T, icp_settings);
    if (!fit) return fit.error().prepend("head calibration: ");
    out.icp = std::move(*fit);
    T = out.icp.T_target_source;
    ++out.scale_rounds;
    if (!settings.fit_motion_scale || out.scale_rounds >= settings.max_scale_rounds) break;
    const Evaluation e = evaluate(scaled(raw, scale), T, *artefact.distance, settings);
    normal_equations(e, raw, T, &scale, H, g);
    const double dk = Eigen::VectorXd(H.ldlt().solve(-g))[6];
    if (!std::isfinite(dk)) break;
    scale.k += dk;
    if (std::abs(dk) < settings.scale_convergence) break;
  }
  if (out.icp.converged) return std::nullopt;
  return fail(ErrorCode::kAnalysisFailed,
              "head calibration: the fit did not converge (" + out.icp.stop_reason + ")");
}

Error refusal(const std::vector<CalibrationFreeDirection>& loose) {
  std::string names;
  for (const auto& f : loose) names += (names.empty() ? "" : "; ") + f.description;
  return fail(ErrorCode::kAnalysisFailed,
              "head calibration: the view leaves " + std::to_string(loose.size()) +
                  " direction(s) free: " + names +
                  " (a plane or a profile extruded along the motion does not fix them)");
}

/// Cov = sigma^2 H^-1, sigma^2 the inliers' residual variance with the fitted parameters'
/// degrees of freedom taken off (linear least squares, e.g. Bjorck 1996, section 1.1.4).
void set_uncertainty(const Evaluation& e, const Eigen::MatrixXd& H, HeadCalibration& out) {
  double sum2 = 0.0;
  for (std::size_t i = 0; i < e.residual.size(); ++i)
    if (e.inlier[i]) sum2 += e.residual[i] * e.residual[i];
  const auto m = static_cast<std::size_t>(H.rows());
  out.covariance = (sum2 / static_cast<double>(e.inliers - m)) * H.inverse();
  for (int j = 0; j < 3; ++j) {
    out.rotation_sigma_deg[j] = std::sqrt(out.covariance(j, j)) * kRadToDeg;
    out.translation_sigma_mm[j] = std::sqrt(out.covariance(3 + j, 3 + j));
  }
  if (m == 7) out.motion_scale_sigma = std::sqrt(out.covariance(6, 6));
}

}  // namespace

IcpSettings calibration_icp_settings() {
  IcpSettings s;
  s.method = IcpMethod::kPointToPlane;
  s.max_iterations = 60;
  s.trimmed_fraction = 0.0;  // outliers go by their residual, not by a share
  s.inlier_sigma_factor = 3.0;
  s.min_inlier_threshold_mm = 0.005;
  s.kernel = RobustKernel::kHuber;
  s.kernel_scale_mm = 0.05;
  s.error_ratio_stop = 0.0;
  s.convergence_rotation_deg = 1e-7;
  s.convergence_translation_mm = 1e-6;
  return s;
}

Expected<HeadCalibration> calibrate_head(const std::vector<Vec3>& head_points,
                                         const PartModel& artefact,
                                         const HeadCalibrationSettings& settings,
                                         std::vector<CalibrationFreeDirection>* free) {
  if (auto bad = check_input(head_points, artefact, settings)) return *bad;
  // Rigid fits and scale steps on an even stride of the points, from the global fit's pose.
  const std::vector<Vec3> raw = strided(head_points, settings.max_points);
  MotionScale scale{settings.motion_axis, 0.0, 1.0};
  for (const Vec3& p : raw) scale.centre += p[scale.axis] / static_cast<double>(raw.size());
  auto start = initial_pose(raw, artefact, settings);
  if (!start) return start.error();
  HeadCalibration out;
  Transform T = *start;
  if (auto failed = fit_rounds(raw, artefact, settings, T, scale, out)) return *failed;
  // Residuals, outliers and the normal matrix at the result; free directions refuse the view.
  const Evaluation e = evaluate(scaled(raw, scale), T, *artefact.distance, settings);
  if (e.inliers < kMinPoints)
    return fail(ErrorCode::kAnalysisFailed, "head calibration: only " + std::to_string(e.inliers) +
                                                " points lie on the artefact after the fit");
  Eigen::MatrixXd H;
  Eigen::VectorXd g;
  normal_equations(e, raw, T, settings.fit_motion_scale ? &scale : nullptr, H, g);
  std::vector<CalibrationFreeDirection> loose =
      free_directions(H.topLeftCorner<6, 6>(), rms_radius(e), e.centre,
                      settings.min_direction_ratio, &out.weakest_direction_ratio);
  if (free) *free = loose;
  if (!loose.empty()) return refusal(loose);
  set_uncertainty(e, H, out);
  // T S_c(k) p = R S_0(k) p + t + (1 - k) c R e_m: the transform for the scale about 0, the one
  // the driver's motion_axis = k R e_m applies.
  out.T_station_head = T;
  out.T_station_head.translation() += (1.0 - scale.k) * scale.centre * T.linear().col(scale.axis);
  out.motion_scale = scale.k;
  out.rms_mm = e.rms;
  out.p95_mm = e.p95;
  out.points = head_points.size();
  out.fitted_points = raw.size();
  out.inliers = e.inliers;
  out.centre = e.centre;
  return out;
}

}  // namespace springscan::analysis
