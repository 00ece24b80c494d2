#pragma once
// A produced part (simulators/parts/produced_part.hpp) scanned as a laser line scanner or a
// tactile probe sees it (docs/springback.md, "Parts as produced").
//
// Scan model: parallel rays along the view direction on a regular pattern: laser lines along
// `line_direction` (across the view), `line_spacing_mm` apart, each with a fixed point spacing.
// Each ray returns the first surface it meets on the produced part's tessellation (a z-buffer
// over the pattern's rays: exact ray casting for parallel rays), so self-occlusion is handled
// and, on a solid, back faces are never seen. Returns from surfaces seen more obliquely than
// `max_incidence_deg` are dropped. The hit is snapped to the CAD surface of its face (planes,
// cylinders exactly) and produced from there, so points lie on the produced part, not on its
// chords. Then Gaussian noise along the ray, outliers along the ray, missing areas (random
// discs) and the pose T_scan_part. Deterministic by seed, whatever the thread count.

#include <cstdint>
#include <vector>

#include "analysis/core/expected.hpp"
#include "analysis/core/point_cloud.hpp"
#include "simulators/parts/produced_part.hpp"

namespace springscan::parts {

struct LaserScanSettings {
  Vec3 view_direction = -Vec3::UnitZ();  ///< the rays' direction (scanner to part), part frame
  Vec3 line_direction = Vec3::UnitX();   ///< along each laser line (its part across the view)
  double line_spacing_mm = 0.5;          ///< distance between neighbouring lines
  double point_spacing_mm = 0.0;         ///< between points along a line; 0: line_spacing_mm
  /// > 0: both spacings (equal) chosen so that the scan has about this many points (within a
  /// few percent, after missing areas); overrides the two spacings.
  std::int64_t point_count = 0;
  double max_incidence_deg = 80.0;  ///< no return from surfaces seen more obliquely
  double noise_sigma_mm = 0.0;      ///< Gaussian noise along the ray
  double outlier_fraction = 0.0;    ///< share of points moved along their ray, [0, 0.5]
  double outlier_max_mm = 3.0;      ///< outliers move uniformly within +-this
  double missing_fraction = 0.0;    ///< share of the seen area cut out, [0, 0.8]
  int missing_patches = 3;          ///< round holes (in the view plane) that share it
  Transform T_scan_part = Transform::Identity();  ///< pose of the part in the scanner frame
  std::uint64_t seed = 1;                         ///< the same seed gives the same scan
  int threads = 0;  ///< 0: all cores (the result does not depend on it)
};

/// A simulated scan and its truth.
struct LaserScan {
  /// Scanner frame: points, true (noise-free) normals, and the CAD face each point came from.
  PointCloud cloud;
  std::vector<Vec3> cad_points;       ///< per point: the CAD point it is the produced image of
  std::vector<std::uint8_t> outlier;  ///< per point: 1 for an outlier
  Transform T_scan_part = Transform::Identity();
  double line_spacing_mm = 0.0;   ///< as used
  double point_spacing_mm = 0.0;  ///< as used
  std::int64_t lines = 0;         ///< laser lines over the part
  std::int64_t points_per_line = 0;
  std::int64_t hits = 0;      ///< rays that met the part (front faces)
  std::int64_t grazing = 0;   ///< of those, dropped for incidence
  std::int64_t missing = 0;   ///< dropped in missing areas
  std::int64_t outliers = 0;  ///< points moved as outliers
};

/// Scans `part` (produced with make_produced_part). Errors: no tessellation, a zero or
/// view-parallel direction, spacings or fractions out of range (named with the value), a
/// pattern of more than 100 million rays.
Expected<LaserScan> laser_scan(const ProducedPart& part, const LaserScanSettings& settings = {});

struct ProbeSettings {
  Vec3 direction = -Vec3::UnitZ();  ///< the probe's approach direction (part frame)
  double spacing_mm = 10.0;         ///< grid spacing (across the approach direction)
  double max_incidence_deg = 60.0;  ///< the probe skips points on steeper surfaces
  double noise_sigma_mm = 0.002;    ///< along the approach direction
  Transform T_scan_part = Transform::Identity();
  std::uint64_t seed = 1;
};

/// A tactile probe: a grid of points on the side of `part` facing against `direction`, each the
/// first contact along the approach (the same ray model as laser_scan, without outliers or
/// missing areas).
Expected<LaserScan> probe_grid(const ProducedPart& part, const ProbeSettings& settings = {});

}  // namespace springscan::parts
