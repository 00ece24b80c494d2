#pragma once
// Analytic parts from a ProfileSpec (simulators/parts/sheet_profile.hpp): the exact PartModel of
// the nominal profile (samples, segmentation, exact distance) and simulated scans of the part as
// produced, bent with a known springback per bend. Tests, benchmarks and the scanner simulator
// build their ground truth with these two functions.
//
// Face ids: one per path element, in path order: flange i is face 2i, bend i is face 2i + 1
// (the element index of profile_path()). Flange::id == i, Bend::id == i.
//
// Placement of the bent part (the ground truth of every springback test): the produced part
// is the same profile with each bend angle reduced in magnitude by its springback, built by
// profile_path() from the same origin, so flange 0 stays exactly where it is in the nominal
// part and each later flange turns about the bend lines before it. Flange lengths and bend
// radii are unchanged. `T_scan_part` then places that part in the scanner frame.

#include <cstdint>
#include <memory>
#include <vector>

#include "analysis/core/expected.hpp"
#include "analysis/core/part_model.hpp"
#include "simulators/parts/sheet_profile.hpp"

namespace springscan::parts {

// The parts are built of the analysis types (points, models, segmentation).
using namespace springscan::analysis;

struct SheetSamplingSettings {
  int sample_count = 40000;  ///< target number of model samples (a grid; the count is close)
};

/// Face id of path element `element_index` (the index into profile_path()).
inline int profile_face_id(int element_index) { return element_index; }

/// The nominal part of `spec`: samples of the reference side on an even grid in (arc length,
/// width) with exact normals and face ids; the exact segmentation (flange i between bends i-1
/// and i; bend axis through the arc centre at mid-width, oriented so that flange b is flange a
/// turned by +nominal_angle_deg about it); and an exact, thread-safe SurfaceDistance.
/// Errors: an invalid spec, or sample_count outside [1, 50'000'000].
Expected<PartModel> profile_part_model(const ProfileSpec& spec,
                                       const SheetSamplingSettings& settings = {});

/// The exact closest point on the reference side of `spec` (lines and arcs extruded over
/// [0, width]); signed by the reference-side normal. Requires is_valid(spec). Immutable, so
/// concurrent calls to closest() are safe.
std::shared_ptr<const SurfaceDistance> profile_surface_distance(const ProfileSpec& spec);

/// The part as produced: `nominal` with each bend angle a_i replaced by
/// sign(a_i) * (|a_i| - springback_deg[i]). Positive springback opens the bend.
/// Errors: wrong number of values, or a produced angle outside (0, 180) degrees.
Expected<ProfileSpec> produced_profile(const ProfileSpec& nominal,
                                       const std::vector<double>& springback_deg);

struct ScanSimulationSettings {
  std::int64_t point_count = 50000;  ///< points in the scan (after missing areas are cut out)
  double noise_sigma_mm = 0.02;      ///< Gaussian noise along the surface normal
  double outlier_fraction = 0.0;     ///< share of points replaced by outliers, [0, 0.5]
  double outlier_max_mm = 3.0;       ///< outliers sit uniformly within +-this along the normal
  double missing_fraction = 0.0;     ///< share of the surface left unscanned, [0, 0.8]
  int missing_patches = 1;           ///< rectangular holes (in arc length x width) that share it
  bool with_normals = false;         ///< also return the exact (noise-free) normals
  Transform T_scan_part = Transform::Identity();  ///< pose of the produced part in the scan
  std::uint64_t seed = 1;                         ///< the same seed gives the same scan
};

/// A simulated scan of the produced part (see produced_profile and the placement note above):
/// uniform random points of the reference side, noise, outliers and missing patches as set,
/// in the scanner frame. Holes are placed at random inside the surface; overlapping holes
/// make the missing share slightly smaller than asked.
/// Errors: as produced_profile, or settings out of range (named with the value).
Expected<PointCloud> simulate_scan(const ProfileSpec& nominal,
                                   const std::vector<double>& springback_deg,
                                   const ScanSimulationSettings& settings = {});

}  // namespace springscan::parts
