#pragma once
// Profiles that are more than rigid flanges: the ground truth of the flange-shape and
// angle-along-the-bend measurements (docs/springback.md "Beyond rigid flanges"). A nominal
// ProfileSpec (sheet_profile.hpp) is produced with
//   - springback per bend that varies linearly along the bend line (y),
//   - sidewall curl: a flange bent to a constant signed radius across its width (its length
//     kept), the turns of the bends next to it reduced by half its sweep each (a first flange
//     starts turned back by half its sweep), so every flange's chord keeps its nominal
//     direction (a curled wall bows out between its nominal ends),
//   - twist: the whole section turning linearly about the y axis along y,
//   - flange lengths changed (a free edge moved along the sheet),
//   - a flange's side edge at y = width moved along y (a trim edge off: the flange alone
//     reaches to width + change, its bends and the other flanges to width).
// The section at every y is built exactly (lines and arcs), so every figure below is known in
// closed form: the angle each bend turns at any y, each flange's curl radius and twist rate.
//
// Conventions as sheet_profile.hpp: the section lies in the x-z plane at extrusion coordinate
// y, the path is the reference side, a positive turn goes left (+x towards +z). A curl radius
// is positive when the flange turns left along the path, i.e. its centre of curvature lies on
// the side the reference-side normal points to. Twist is the rate at which a flange's normal
// turns right-handed about the bend line per 100 mm along it (a chirality: it does not depend
// on which way the line is oriented).

#include <vector>

#include "analysis/core/expected.hpp"
#include "analysis/core/point_cloud.hpp"
#include "simulators/parts/sheet_part.hpp"
#include "simulators/parts/sheet_profile.hpp"

namespace springscan::parts {

struct ProfileShape {
  std::vector<double> springback_deg;  ///< per bend at mid-width (y = width / 2); empty: 0
  /// Per bend: change of its springback per 100 mm along +y; empty: 0.
  std::vector<double> springback_gradient_deg_per_100mm;
  std::vector<double> curl_radius_mm;  ///< per flange, signed (see above); 0: flat; empty: flat
  /// The whole section turns about the y axis through the middle of the nominal path (by arc
  /// length), right-handed about +y, by this per 100 mm along +y; 0 at mid-width.
  double twist_deg_per_100mm = 0.0;
  /// Per flange: its length as produced minus the nominal (a free edge moved along the sheet:
  /// overhang > 0, draw-in < 0); empty: 0.
  std::vector<double> length_change_mm;
  /// Per flange: where its side edge at y = width lies as produced minus the nominal (along +y:
  /// overhang > 0, draw-in < 0); empty: 0. Scans only (simulate_shaped_scan): shaped_section
  /// gives the section at any y.
  std::vector<double> width_change_mm;
};

/// The produced section at extrusion coordinate `y_mm`: elements in path order as
/// profile_path() gives them (flange i, bend i, flange i+1, ...); a curled flange is an arc
/// (kind kArc with flange_index set). Errors: sizes that do not match the spec, a curl sweeping
/// half a turn or more, or a produced turn that changes sign or reaches 180 degrees.
Expected<std::vector<ProfileElement>> shaped_section(const ProfileSpec& nominal,
                                                     const ProfileShape& shape, double y_mm);

/// The angle the sheet turns at bend `bend` at `y_mm` (degrees, > 0): the sweep of the bend's
/// arc, which equals the angle between the tangent planes of the two flanges at their ends next
/// to the bend (NUMISHEET'93's definition on a curled wall). Requires a valid shape.
double shaped_bend_angle_deg(const ProfileSpec& nominal, const ProfileShape& shape, int bend,
                             double y_mm);

/// Flange `flange`'s twist (degrees per 100 mm along the bend line, sign as above): the
/// section's twist plus the change along y of every bend before it on the path.
double shaped_flange_twist_deg_per_100mm(const ProfileSpec& nominal, const ProfileShape& shape,
                                         int flange);

/// A scan of the shaped part: `settings.point_count` points uniform in (arc length, y), noise
/// along the section's normal, outliers and the pose as in simulate_scan (missing patches are
/// not supported: missing_fraction must be 0). Deterministic for a seed.
Expected<PointCloud> simulate_shaped_scan(const ProfileSpec& nominal, const ProfileShape& shape,
                                          const ScanSimulationSettings& settings = {});

}  // namespace springscan::parts
