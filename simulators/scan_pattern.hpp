#pragma once
// What the simulated scanner measures: a part given as a dense point cloud of its surface (part
// frame, mm), seen by a laser line moving along its motion axis, or touched by a tactile probe
// on a grid. Pure functions with a caller-owned random generator, so a fixed seed gives the
// same scan. Output is in the device's own frames (sensor plane, machine frame), ready to be
// put on the wire (docs/device-protocol.md §4).

#include <cstdint>
#include <random>
#include <vector>

#include "analysis/core/point_cloud.hpp"
#include "drivers/conversion.hpp"
#include "drivers/messages.hpp"

namespace springscan::simulators {

/// Measurement imperfections shared by both kinds.
struct NoiseSettings {
  double sigma_mm = 0.02;         ///< Gaussian noise along the measuring direction
  double outlier_fraction = 0.0;  ///< share of points displaced by up to outlier_mm
  double outlier_mm = 2.0;        ///< largest outlier displacement
  double missing_fraction = 0.0;  ///< share of points reported missing (laser: NaN)
};

struct LaserPatternSettings {
  drivers::LaserCalibration calibration;  ///< the sensor mount (the driver is given the same)
  double step_mm = 1.0;                   ///< encoder travel between profiles
  int points_per_profile = 256;           ///< bins across the laser line, 1..4096
  double slice_half_thickness_mm = 0.25;  ///< surface points this close to the plane are seen
  /// > 0: a dual-head line scanner, two heads tilted by +-this about the motion axis (both in
  /// the laser plane of `calibration`), each seeing what faces it, both heads' points sent in
  /// the primary head's frame (the device merges them); 0: the one head of `calibration`.
  /// A part's walls parallel to the view give no return to one head looking straight down.
  double head_tilt_deg = 0.0;
  /// With two heads: the second head turned on its mount by this much beyond head_tilt_deg,
  /// about the motion axis, while the device still merges its readings as mounted (a head
  /// that drifted since the calibration; its points turn against the first head's). 0: none.
  double second_head_drift_deg = 0.0;
};

struct ProbePatternSettings {
  drivers::ProbeCalibration calibration;     ///< machine frame in the part frame (ground truth)
  analysis::Vec3 direction{0.0, 0.0, -1.0};  ///< approach direction, part frame, unit
  double grid_step_mm = 5.0;                 ///< node spacing across the approach direction
  double capture_radius_mm = 0.5;            ///< surface points this close to a node's line
  float stylus_radius_mm = 1.0f;             ///< reported with every record
  int records_per_frame = 64;                ///< 1..1024
};

struct SimulatedProfile {
  double encoder_mm = 0.0;
  std::vector<drivers::SensorPoint> points;
};

/// Profiles covering the part along the motion axis. Each bin across the line keeps the
/// surface point nearest to the sensor (occlusion); empty bins are NaN. With two heads, the
/// second head's profiles follow the first's (same encoder positions).
std::vector<SimulatedProfile> laser_profiles(const analysis::PointCloud& surface,
                                             const LaserPatternSettings& settings,
                                             const NoiseSettings& noise, std::mt19937& rng);

/// One probe record per grid node whose line meets the part: the first surface point the
/// stylus reaches, as a stylus centre in the machine frame.
std::vector<drivers::ProbeRecord> probe_grid(const analysis::PointCloud& surface,
                                             const ProbePatternSettings& settings,
                                             const NoiseSettings& noise, std::mt19937& rng);

}  // namespace springscan::simulators
