#pragma once
// A laser line head's raw scan of a part given as triangles (the calibration artefact: planes
// only, so its tessellation is the exact surface), as the head reports it in its own frame,
// for testing `springscan calibrate` (docs/calibration.md) against a known mount.
//
// The head frame is (x along the laser line, z range, encoder): a right-handed frame when the
// head travels along x × z (the drivers' default mount, LaserCalibration). A ray leaves the head
// at (x, 0, e) along +z; in the station it starts at T_station_head * (x, 0, k e), where k is
// the true station travel per encoder millimetre (an encoder scale error is k != 1), and
// returns the first triangle it meets. The head reports (x, range + noise, e).

#include <cstdint>
#include <string>
#include <vector>

#include "analysis/core/expected.hpp"
#include "analysis/core/point_cloud.hpp"

namespace springscan::parts {

struct HeadScanSettings {
  analysis::Transform T_station_head = analysis::Transform::Identity();  ///< the true mount
  double motion_scale = 1.0;  ///< true station travel per encoder mm
  double x_min_mm = -100.0;   ///< laser line extent along head x
  double x_max_mm = 100.0;
  double encoder_min_mm = -100.0;  ///< travel
  double encoder_max_mm = 100.0;
  double point_spacing_mm = 1.0;    ///< along the line
  double line_spacing_mm = 1.0;     ///< encoder step between lines
  double max_incidence_deg = 80.0;  ///< no return from surfaces seen more obliquely
  double noise_sigma_mm = 0.02;     ///< Gaussian, along the ray
  double outlier_fraction = 0.0;    ///< share of returns moved along the ray, [0, 0.5]
  double outlier_max_mm = 3.0;      ///< uniformly within +-this
  std::uint64_t seed = 1;
};

/// The head's points (head frame, mm; normals left empty). Errors: an empty mesh, spacings not
/// positive, fractions out of range, more than 10 million rays.
analysis::Expected<analysis::PointCloud> head_scan(const analysis::TriangleMesh& mesh,
                                                   const HeadScanSettings& settings = {});

/// A demo station's head: nominal mount and the mount as built (the calibration tests, the
/// artefact program and docs/calibration.md use these).
struct DemoHead {
  std::string name;
  analysis::Transform nominal = analysis::Transform::Identity();  ///< T_station_head, drawing
  analysis::Transform truth = analysis::Transform::Identity();    ///< as mounted: 0.5 degree
                                                                  ///< and 2 mm off the drawing
};

/// Three heads 240 mm above the shipped artefact's top (simulators/parts/artefact.hpp): "a"
/// straight down, "b" tilted 25 degrees about x, "c" tilted -25 degrees about y, each mounted
/// 0.5 degree and 2 mm off its nominal pose, about and along different axes.
std::vector<DemoHead> demo_heads();

/// head_scan settings that cover the shipped artefact from a demo head's mount: 1.5 mm
/// spacing, noise sigma 0.02 mm, 1 % outliers up to 3 mm.
HeadScanSettings demo_head_scan(const analysis::Transform& truth, double motion_scale,
                                std::uint64_t seed);

}  // namespace springscan::parts
