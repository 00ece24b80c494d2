#pragma once
// Sheet-metal test parts with round holes and slots: a bent profile (cad_profile.hpp) as a solid,
// cut through by cylinders and stadiums with OpenCASCADE. The datum alignment's own test parts
// (brackets, trays, panels; docs/alignment.md "Accuracy"), whose holes and slots the test places
// itself, so their true positions are known.

#include <vector>

#include "analysis/cad/import.hpp"
#include "simulators/parts/sheet_profile.hpp"

namespace springscan::parts {

// The parts are built of the analysis types (points, models, segmentation).
using namespace springscan::analysis;

/// A round hole (length_mm = 0) or a slot (length_mm > diameter_mm, its long axis `along`) cut
/// through the sheet at `centre` along `axis` (both CAD frame, mm; the cut reaches 50 mm to
/// either side of `centre` along the axis).
struct Cutout {
  Vec3 centre = Vec3::Zero();
  Vec3 axis = Vec3::UnitZ();   ///< unit
  double diameter_mm = 0.0;    ///< a slot's width
  double length_mm = 0.0;      ///< a slot's overall length; 0: a round hole
  Vec3 along = Vec3::UnitX();  ///< unit, across `axis`: a slot's long direction
};

/// The solid of `spec` (thickness > 0) with `cutouts` cut through it. Errors: an invalid spec,
/// no thickness, a cut OpenCASCADE could not make.
Expected<CadShape> make_profile_with_cutouts(const ProfileSpec& spec,
                                             const std::vector<Cutout>& cutouts,
                                             const CadImportSettings& settings = {});

}  // namespace springscan::parts
