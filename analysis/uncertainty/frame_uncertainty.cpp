#include "analysis/uncertainty/frame_uncertainty.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

namespace springscan::analysis {
namespace {

using Mat6 = Eigen::Matrix<double, 6, 6>;
using Vec6 = Eigen::Matrix<double, 6, 1>;

double sq(double x) { return x * x; }

// The largest rms move, over the corners of [lo, hi], of the motion with covariance `cov`
// (rotation about `c` first, then translation).
double largest_move(const Mat6& cov, const Vec3& c, const Vec3& lo, const Vec3& hi) {
  double worst = 0.0;
  for (int corner = 0; corner < 8; ++corner) {
    const Vec3 x((corner & 1) ? hi.x() : lo.x(), (corner & 2) ? hi.y() : lo.y(),
                 (corner & 4) ? hi.z() : lo.z());
    double var = 0.0;
    for (int axis = 0; axis < 3; ++axis) {
      const Vec3 e = Vec3::Unit(axis);
      Vec6 g;
      g << (x - c).cross(e), e;  // e . (w x (x - c) + t)
      var += g.dot(cov * g);
    }
    worst = std::max(worst, std::sqrt(var));
  }
  return worst;
}

// The standard uncertainty of a value whose change is g . (rotation, translation): the
// covariance's part (the departed pairs' move of the frame included, departure_move), and the
// departure as a move of about its size in a direction not known, isotropic (a third of its
// variance along each axis, as the frame's U takes d for the whole move).
double sensitivity_sigma(const FrameUncertainty& frame, const Vec6& g) {
  const double departure2 =
      frame.departure_mm * frame.departure_mm * g.tail<3>().squaredNorm() / 3.0;
  return std::sqrt(std::max(0.0, g.dot(frame.covariance * g) + departure2));
}

// What the part's departure does to the frame (rotation about `c` in rad, translation in mm):
// the fit's move were its most departed pairs (those beyond the `share` quantile of |r|, the
// farthest 1 % left out as outliers) left out, (J^T J)^-1 sum j r over them, a one-step
// least-squares update from the fit's own normal matrix of all its pairs. Directions the pairs
// leave free (an extrusion's length) do not move.
Vec6 departed_move(const std::vector<Vec6>& rows, const std::vector<double>& residuals,
                   const Vec6& scale, double cut, double trim) {
  Mat6 normal = Mat6::Zero();
  Vec6 pull = Vec6::Zero();
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const double r = std::abs(residuals[i]);
    if (r > trim) continue;
    normal += rows[i] * rows[i].transpose();
    if (r > cut) pull += rows[i] * residuals[i];
  }
  const Mat6 scaled =
      scale.cwiseInverse().asDiagonal() * normal * scale.cwiseInverse().asDiagonal();
  const Eigen::SelfAdjointEigenSolver<Mat6> eig(scaled);
  const Vec6 b = scale.cwiseInverse().asDiagonal() * pull;
  Vec6 x = Vec6::Zero();
  const double largest = eig.eigenvalues()(5);
  for (int k = 0; k < 6; ++k)
    if (eig.eigenvalues()(k) > 1e-6 * largest)
      x += eig.eigenvectors().col(k) * (eig.eigenvectors().col(k).dot(b) / eig.eigenvalues()(k));
  return scale.cwiseInverse().asDiagonal() * x;
}

}  // namespace

FrameUncertainty frame_uncertainty(const std::vector<Vec3>& points, const KdTree& tree,
                                   const std::vector<Vec3>& normals, const UncertaintySettings& st,
                                   double pair_distance_mm) {
  FrameUncertainty out;
  if (points.empty() || normals.size() != tree.size()) return out;
  Vec3 c = Vec3::Zero(), lo = points.front(), hi = points.front();
  for (const Vec3& p : points) c += p, lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
  c /= static_cast<double>(points.size());
  // The pairs' rows and residuals.
  std::vector<Vec6> rows;
  std::vector<double> residuals;
  rows.reserve(points.size());
  residuals.reserve(points.size());
  // The same pairs to the surface itself (below): the nearest tangent plane of the nearest
  // samples, for the covariance and the departed pairs' move.
  std::vector<Vec6> surface_rows;
  std::vector<double> surface_residuals;
  constexpr std::size_t kSurfaceCandidates = 6;
  const double on_surface_mm = 2.0 * std::max(st.scanner_sigma_mm, 0.01);
  // At most kMaxPairs pairs, evenly through the points: J^T J of all of them is `stride` x that
  // of every stride-th (the covariance's scale is set back below).
  constexpr std::size_t kMaxPairs = 10000;
  const std::size_t stride = std::max<std::size_t>(1, points.size() / kMaxPairs);
  for (std::size_t i = 0; i < points.size(); i += stride) {
    const Vec3& p = points[i];
    const auto nn = tree.nearest(p, pair_distance_mm);
    if (!nn) continue;
    const Vec3& n = normals[nn->index];
    Vec6 j;
    j << (p - c).cross(n), n;
    rows.push_back(j);
    residuals.push_back(n.dot(p - tree.points()[nn->index]));
    // The surface's own residual: of the 6 nearest samples, the one whose tangent plane the
    // point lies nearest. A sheet thinner than the samples' spacing pairs a point with the
    // other face's sample (its residual the thickness: 0.7 mm on the side panel seen from
    // below, robust scale 0.45-0.75 mm at a noise of 0.02) where its own face's lies a little
    // farther to the side; the best fit, on the exact surface, does not see those, and their
    // move when left out turned the frame's U by 0.01-0.04 deg (development seeds). Only where
    // the nearest sample's plane lies off the point beyond the noise (the queries' cost: most
    // pairs are on their own face).
    double best = residuals.back();
    Vec6 best_row = j;
    std::uint32_t idx[kSurfaceCandidates];
    double d2[kSurfaceCandidates];
    const std::size_t found =
        std::abs(best) > on_surface_mm ? tree.knn(p, kSurfaceCandidates, idx, d2) : 0;
    for (std::size_t q = 0; q < found; ++q) {
      if (d2[q] > pair_distance_mm * pair_distance_mm) break;
      const Vec3& nq = normals[idx[q]];
      const double r = nq.dot(p - tree.points()[idx[q]]);
      if (std::abs(r) < std::abs(best)) best = r, best_row << (p - c).cross(nq), nq;
    }
    surface_rows.push_back(best_row);
    surface_residuals.push_back(best);
  }
  out.pairs = rows.size();
  if (out.pairs < 6) return out;
  std::vector<double> magnitude(residuals.size());
  for (std::size_t i = 0; i < residuals.size(); ++i) magnitude[i] = std::abs(residuals[i]);
  // The part's departure from the CAD (springback, curl: the pairs' rms with the farthest 5 %
  // left out): the best fit of a deformed part moves with what of it the scan sees and the fit
  // keeps, by about that much (the method's error, u = d). The noise is not taken off: the
  // robust scale takes in the deformation itself where it covers half the seen surface (the
  // calibration study's brackets seen from below: scale 0.14 mm, departure less the scale 0,
  // the frame 0.29 deg off), and the fit points are the reduced scan's, whose noise is a
  // fraction of the scanner's.
  std::sort(magnitude.begin(), magnitude.end());
  double sum2 = 0.0;
  const std::size_t kept = std::max<std::size_t>(1, magnitude.size() * 95 / 100);
  for (std::size_t i = 0; i < kept; ++i) sum2 += magnitude[i] * magnitude[i];
  const double departure_mm = std::sqrt(sum2 / static_cast<double>(kept));
  // The covariance from the fit's scatter about the surface itself (the surface pairs), at a
  // robust scale (1.4826 MAD: the pairs include springback's own deviations and outliers); the
  // departure above keeps the nearest sample's residual (what the fit's pairing sees).
  std::vector<double> surface_magnitude(surface_residuals.size());
  for (std::size_t i = 0; i < surface_residuals.size(); ++i)
    surface_magnitude[i] = std::abs(surface_residuals[i]);
  std::sort(surface_magnitude.begin(), surface_magnitude.end());
  out.sigma_mm =
      std::max(1.4826 * surface_magnitude[surface_magnitude.size() / 2], st.scanner_sigma_mm);
  Mat6 normal = Mat6::Zero();
  for (std::size_t i = 0; i < surface_rows.size(); ++i)
    if (std::abs(surface_residuals[i]) <= 3.0 * out.sigma_mm)
      normal += surface_rows[i] * surface_rows[i].transpose();
  normal *= static_cast<double>(stride);
  // Rotation scaled by the points' size, so that the eigenvalues compare.
  const double radius = std::max(0.5 * (hi - lo).norm(), 1.0);
  Vec6 scale;
  scale << Vec3::Constant(radius), Vec3::Ones();
  const Mat6 scaled =
      scale.cwiseInverse().asDiagonal() * normal * scale.cwiseInverse().asDiagonal();
  const Eigen::SelfAdjointEigenSolver<Mat6> eig(scaled);
  const double largest = eig.eigenvalues()(5);
  if (!(largest > 0.0)) return out;
  // Determined directions: sigma^2 / eigenvalue; a free one (an extrusion's length) is fixed by
  // the part's ends to about free_direction_mm.
  Vec6 variance;
  for (int k = 0; k < 6; ++k) {
    const double value = eig.eigenvalues()(k);
    const bool fixed = value > 1e-6 * largest;
    variance(k) =
        fixed ? out.sigma_mm * out.sigma_mm / value : st.free_direction_mm * st.free_direction_mm;
  }
  Mat6 cov = eig.eigenvectors() * variance.asDiagonal() * eig.eigenvectors().transpose();
  cov = scale.cwiseInverse().asDiagonal() * cov * scale.cwiseInverse().asDiagonal();
  // A translation the surface fixes only weakly (its information below the ends' rule,
  // registration/boundary.hpp free_eigenvalue_ratio) is placed by the part's ends: there the
  // covariance of a few points (a hole's wall, an edge-on wall) does not tell, the ends do.
  Eigen::Matrix3d info = Eigen::Matrix3d::Zero();
  for (std::size_t i = 0; i < surface_rows.size(); ++i)
    if (std::abs(surface_residuals[i]) <= 3.0 * out.sigma_mm)
      info += surface_rows[i].tail<3>() * surface_rows[i].tail<3>().transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> moves(info);
  constexpr double kWeakTranslationRatio = 2e-2;  // as free_eigenvalue_ratio's default
  for (int k = 0; k < 3; ++k) {
    if (!(moves.eigenvalues()(k) < kWeakTranslationRatio * moves.eigenvalues()(2))) continue;
    const Vec3 u = moves.eigenvectors().col(k);
    const double along = u.dot(cov.bottomRightCorner<3, 3>() * u);
    const double free2 = st.free_direction_mm * st.free_direction_mm;
    if (along < free2) cov.bottomRightCorner<3, 3>() += (free2 - along) * u * u.transpose();
  }
  // The departure as a weakly determined direction of the fit feels it (v_k of the scaled
  // normal matrix, its information below 5 % of the largest): the pairs' mean square residual
  // weighted by their rows' share of that direction, the farthest 1 % left out (outliers). A
  // direction that rests on a few points (a bracket seen from above: its edge-on wall places
  // the part across it) moves with their departure, which the part's rms hides (the wall a few
  // % of the pairs, its sprung tip the farthest of them: the study's one-sided nema bracket
  // 1 mm off against U 0.14). Beyond the isotropic departure, along that direction (rotation
  // scaled by the radius: a turn of d / radius). Every direction so (not only the weak ones)
  // padded the well-seen families' translation 3.5x (study, development seeds). Its translation
  // only: on a flat panel its weak direction is the turn about the normal, which its walls'
  // few pairs fix, and their residual there turned it by 0.13-0.15 deg where the frame was
  // 0.002-0.007 off (the departed pairs' move below tells what they do to the rotation).
  constexpr double kWeakShare = 0.05;
  Mat6 weak = Mat6::Zero();
  const double trim = magnitude[std::min(magnitude.size() - 1, magnitude.size() * 99 / 100)];
  for (int k = 0; k < 6; ++k) {
    if (!(eig.eigenvalues()(k) < kWeakShare * largest)) continue;
    const Vec6 v = scale.cwiseInverse().asDiagonal() * eig.eigenvectors().col(k);
    double w_sum = 0.0, wr2 = 0.0;
    for (std::size_t i = 0; i < rows.size(); ++i) {
      if (std::abs(residuals[i]) > trim) continue;
      const double w = sq(rows[i].dot(v));
      w_sum += w;
      wr2 += w * sq(residuals[i]);
    }
    if (!(w_sum > 0.0)) continue;
    const double felt2 = wr2 / w_sum;
    if (felt2 <= sq(departure_mm)) continue;
    weak += (felt2 - sq(departure_mm)) * v * v.transpose();
  }
  cov.bottomRightCorner<3, 3>() += weak.bottomRightCorner<3, 3>();
  // What the departure does to the frame: the fit's move were its most departed pairs left
  // out (the farthest 20, 10 or 5 %, whichever turns it most), as a standard uncertainty of
  // 1.2x that along its own direction. The best fit of a sprung part turns with how the fit
  // weighs and samples its departed surface (the reduced scan's points against the whole
  // surface; the Huber corner and the pair distance), not with the departure's size over the
  // part: the development seeds' sprung nema brackets turned 0.16-0.35 deg at 1.2-2.3x this
  // move, the panels 0.002-0.04 deg where the departure over the half-diagonal said
  // 0.07-0.18 (docs/uncertainty.md).
  const auto surface_rank = [&](double share) {
    return surface_magnitude[std::min(
        surface_magnitude.size() - 1,
        static_cast<std::size_t>(share * static_cast<double>(surface_magnitude.size())))];
  };
  const double surface_trim = surface_rank(0.99);
  Vec6 departed = Vec6::Zero();
  for (const double share : {0.80, 0.90, 0.95}) {
    const Vec6 move =
        departed_move(surface_rows, surface_residuals, scale, surface_rank(share), surface_trim);
    if (move.head<3>().norm() > departed.head<3>().norm()) departed = move;
  }
  constexpr double kDepartedFactor = 1.2;
  cov += sq(kDepartedFactor) * departed * departed.transpose();
  out.covariance = cov;
  out.center = c;
  out.departure_mm = departure_mm;
  out.radius_mm = radius;
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> rot(cov.topLeftCorner<3, 3>());
  const double k = st.coverage_factor;
  const double rotation_deg =
      std::sqrt(std::max(0.0, rot.eigenvalues()(2))) * 180.0 / std::numbers::pi;
  out.rotation_deg = k * std::sqrt(rotation_deg * rotation_deg +
                                   st.calibration_angle_deg * st.calibration_angle_deg);
  const double thermal =
      st.expansion_per_k * std::abs(st.temperature_delta_k) * radius / std::sqrt(3.0);
  const double move = largest_move(cov, c, lo, hi);
  const double station_mm = std::hypot(st.calibration_length_mm, thermal);
  out.translation_mm =
      k * std::sqrt(move * move + departure_mm * departure_mm + station_mm * station_mm);
  return out;
}

double frame_statistic_sigma(const FrameUncertainty& frame, const std::vector<Vec3>& points,
                             const std::vector<double>& d, double quantile, const KdTree& tree,
                             const std::vector<Vec3>& normals) {
  if (frame.pairs < 6 || points.empty() || d.size() != points.size() ||
      normals.size() != tree.size())
    return 0.0;
  // The |d| bounds of the ranks next to the quantile: a window of 5 % about a p95 (the quantile
  // moves as the mean of its neighbours' moves), the top 0.1 % for the largest.
  // The bounds from at most kMaxRanked of the values, evenly (ranks to about 0.1 %): a 1M-point
  // scan's full sort would cost more than the rest of the uncertainty stage.
  const double half = quantile >= 1.0 ? 0.001 : 0.025;
  constexpr std::size_t kMaxRanked = 100000;
  const std::size_t every = std::max<std::size_t>(1, d.size() / kMaxRanked);
  std::vector<double> magnitude;
  magnitude.reserve(d.size() / every + 1);
  for (std::size_t i = 0; i < d.size(); i += every) magnitude.push_back(std::abs(d[i]));
  const auto at = [&](double q) {
    const auto rank = static_cast<std::size_t>(std::clamp(q, 0.0, 1.0) *
                                               static_cast<double>(magnitude.size() - 1));
    std::nth_element(magnitude.begin(), magnitude.begin() + static_cast<long>(rank),
                     magnitude.end());
    return magnitude[rank];
  };
  // The part's departure as these exact distances show it (their rms, the farthest 5 % left
  // out, as frame_uncertainty's): the frame's own is of the pairs' residuals to the model
  // samples' tangent planes, which on a coarsely sampled model read the sampling too (a part
  // made exactly as its CAD, samples 1.35 mm apart: 0.3 mm). The smaller of the two.
  FrameUncertainty used = frame;
  {
    const auto kept = static_cast<std::size_t>(0.95 * static_cast<double>(magnitude.size()));
    std::nth_element(magnitude.begin(), magnitude.begin() + static_cast<long>(kept),
                     magnitude.end());
    double sum2 = 0.0;
    for (std::size_t i = 0; i < kept; ++i) sum2 += magnitude[i] * magnitude[i];
    if (kept > 0)
      used.departure_mm = std::min(frame.departure_mm, std::sqrt(sum2 / static_cast<double>(kept)));
  }
  const double lo = at(quantile - half);
  const double hi =
      quantile + half >= 1.0 ? std::numeric_limits<double>::infinity() : at(quantile + half);
  std::vector<std::size_t> near;
  for (std::size_t i = 0; i < d.size(); ++i)
    if (std::abs(d[i]) >= lo && std::abs(d[i]) <= hi) near.push_back(i);
  if (near.empty()) return 0.0;
  // At most kMaxPoints of them, evenly: the mean's sensitivity, not a sum.
  constexpr std::size_t kMaxPoints = 2000;
  const std::size_t stride = std::max<std::size_t>(1, near.size() / kMaxPoints);
  Vec6 g = Vec6::Zero();
  double count = 0.0;
  for (std::size_t k = 0; k < near.size(); k += stride) {
    const std::size_t i = near[k];
    const auto nn = tree.nearest(points[i]);
    if (!nn) continue;
    const Vec3 n = (d[i] < 0.0 ? -1.0 : 1.0) * normals[nn->index];
    g.head<3>() += (points[i] - frame.center).cross(n);
    g.tail<3>() += n;
    count += 1.0;
  }
  if (count == 0.0) return 0.0;
  return sensitivity_sigma(used, g / count);
}

double frame_point_sigma(const FrameUncertainty& frame, const Vec3& point, const Vec3& direction) {
  if (frame.pairs < 6) return 0.0;
  Vec6 g;
  g << (point - frame.center).cross(direction), direction;
  return sensitivity_sigma(frame, g);
}

}  // namespace springscan::analysis
