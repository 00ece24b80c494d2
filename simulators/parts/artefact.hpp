#pragma once
// The station's calibration artefact (docs/calibration.md): a stepped, asymmetric aluminium
// block whose top is cut by inclined planes, so that every head's view of it, from straight
// above or tilted up to 30 degrees, holds planes whose normals span all three directions with
// lever arms in all three: the fit of a head's transform to it leaves no direction free. All
// faces are planes, so its tessellation is exact and a simulated scan of it needs no snapping.

#include <string>

#include "analysis/cad/import.hpp"

namespace springscan::parts {

/// The artefact's main sizes (mm); the cuts scale with them. Defaults: the shipped artefact,
/// demo/calibration-artefact.step.
struct ArtefactSpec {
  double length_mm = 160.0;      ///< base along x
  double width_mm = 100.0;       ///< base along y
  double base_height_mm = 30.0;  ///< base along z
  double step_height_mm = 25.0;  ///< the raised step above the base
  double chamfer_mm = 20.0;      ///< the 45-degree chamfers' depth below the base top
};

/// The artefact as a CadShape (a solid, planar faces only), frame: base corner at the origin,
/// x along its length, z up. Errors: non-positive or inconsistent sizes.
analysis::Expected<analysis::CadShape> make_artefact_shape(
    const ArtefactSpec& spec = {}, const analysis::CadImportSettings& settings = {});

/// Writes the artefact as STEP (AP214, mm). Returns true, or an error naming the path.
analysis::Expected<bool> write_artefact_step(const std::string& path,
                                             const ArtefactSpec& spec = {});

}  // namespace springscan::parts
