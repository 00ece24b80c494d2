#pragma once
// Head calibration (`springscan calibrate`, docs/calibration.md): a scanner head's rigid
// transform into the station frame, fitted to a reference artefact's CAD with the exact CAD
// distance and the one ICP engine (analysis/registration/icp.hpp), robust to outliers; with a
// line scanner's encoder scale when asked. The fit reports its residuals and the transform's
// uncertainty (the inverse of the point-to-plane normal matrix times the residual variance),
// and refuses a view that leaves a direction free.
//
// Head frame: a head's raw points, (x along the laser line, z range, encoder) for a line scanner
// (simulators/parts/head_scan.hpp), or any head frame for other heads. With the motion scale k,
// a raw point p maps to the station as T_station_head * S(k) p, S scaling the motion axis.
//
// Thread safety: a pure function; the artefact's SurfaceDistance is queried concurrently.

#include <string>
#include <vector>

#include "analysis/core/expected.hpp"
#include "analysis/core/part_model.hpp"
#include "analysis/core/point_cloud.hpp"
#include "analysis/registration/global_fit.hpp"
#include "analysis/registration/icp.hpp"

namespace springscan::analysis {

/// The ICP as the calibration runs it: point-to-plane on the exact surface, pairs beyond 3
/// robust sigmas left out (outliers), a Huber kernel at about 2.5 sigma of a good head, run to
/// a negligible update (the error-ratio stop is off: calibration wants the converged answer).
IcpSettings calibration_icp_settings();

struct HeadCalibrationSettings {
  IcpSettings icp = calibration_icp_settings();  ///< every fit on the exact surface
  GlobalFitSettings initial;      ///< the first pose: PCA candidates and ICP on the samples
  bool use_initial_pose = false;  ///< true: start from initial_pose instead (nominal mount)
  Transform initial_pose = Transform::Identity();  ///< T_station_head to start from
  std::size_t max_points = 6000;      ///< the fit uses an even stride of at most this many points
  bool fit_motion_scale = false;      ///< also fit the encoder scale along motion_axis
  int motion_axis = 2;                ///< head-frame axis the encoder scale stretches, 0..2
  int max_scale_rounds = 20;          ///< rigid fit + scale step, at most this many times
  double scale_convergence = 1e-8;    ///< stop when the scale changes less than this
  double outlier_sigma_factor = 3.0;  ///< residuals beyond this many robust sigmas: outliers
  /// A direction is free when its information (normal matrix eigenvalue, rotations scaled by
  /// the view's rms radius) is below this share of the strongest direction's.
  double min_direction_ratio = 2e-3;
  int threads = 0;  ///< 0: all cores (the result does not depend on it)
};

/// A direction of the transform the view does not determine.
struct CalibrationFreeDirection {
  bool rotation = false;      ///< true: a rotation about `axis` through `centre`
  Vec3 axis = Vec3::UnitX();  ///< unit, station frame
  Vec3 centre = Vec3::Zero();
  double ratio = 0.0;       ///< its information / the strongest direction's
  std::string description;  ///< "translation along (0.000, 1.000, 0.000)"
};

struct HeadCalibration {
  Transform T_station_head = Transform::Identity();  ///< raw head frame (scaled) to station
  double motion_scale = 1.0;               ///< station travel per encoder mm (1 unless fitted)
  double rms_mm = 0.0;                     ///< point-to-surface residuals of the inliers
  double p95_mm = 0.0;                     ///< 95th percentile of |residual| of the inliers
  std::size_t points = 0;                  ///< scan points given
  std::size_t fitted_points = 0;           ///< points the fit used (the stride)
  std::size_t inliers = 0;                 ///< of those, within outlier_sigma_factor robust sigmas
  Vec3 centre = Vec3::Zero();              ///< the inliers' centroid, station frame: where the
                                           ///< uncertainties below are given
  Vec3 rotation_sigma_deg = Vec3::Zero();  ///< 1 sigma about the station axes through centre
  Vec3 translation_sigma_mm = Vec3::Zero();  ///< 1 sigma along the station axes at centre
  double motion_scale_sigma = 0.0;           ///< 1 sigma, when fitted
  /// (rx, ry, rz [rad] about centre, tx, ty, tz [mm], and k when fitted): the covariance
  Eigen::MatrixXd covariance;
  double weakest_direction_ratio = 0.0;  ///< the smallest information ratio (1: isotropic)
  IcpResult icp;                         ///< the last rigid fit
  int scale_rounds = 0;
};

/// The directions a point-to-plane normal matrix H (parameters: rotations about `centre` in
/// rad, translations in mm) leaves free: eigenvectors whose eigenvalue, with the rotations
/// scaled by `radius_mm` (the view's rms radius), is below `min_ratio` of the largest, weakest
/// first. `weakest` (when given) gets the smallest ratio.
std::vector<CalibrationFreeDirection> free_directions(const Eigen::Matrix<double, 6, 6>& H,
                                                      double radius_mm, const Vec3& centre,
                                                      double min_ratio, double* weakest = nullptr);

/// Fits the head's transform. Errors (nothing returned): fewer than 100 points, non-finite
/// points, an artefact model without exact distance or samples, no convergence (code
/// kAnalysisFailed), and a view that leaves a direction free (kAnalysisFailed, every free
/// direction named in the message; `free` gets them when given).
Expected<HeadCalibration> calibrate_head(const std::vector<Vec3>& head_points,
                                         const PartModel& artefact,
                                         const HeadCalibrationSettings& settings = {},
                                         std::vector<CalibrationFreeDirection>* free = nullptr);

}  // namespace springscan::analysis
