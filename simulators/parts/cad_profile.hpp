#pragma once
// OpenCASCADE shapes of sheet profiles (simulators/parts/sheet_profile.hpp): the test parts and the
// demo part, whose bends are known exactly from the ProfileSpec.

#include <string>

#include "analysis/cad/import.hpp"
#include "simulators/parts/sheet_profile.hpp"

namespace springscan::parts {

// The parts are built of the analysis types (points, models, segmentation).
using namespace springscan::analysis;

/// The profile as a CadShape: with thickness 0 a shell (the reference side, one face per line and
/// arc of profile_path() extruded along +y); with thickness > 0 a solid bounded by the reference
/// side, the offset side and the end and side faces. Errors: an invalid spec (is_valid).
Expected<CadShape> make_profile_shape(const ProfileSpec& spec,
                                      const CadImportSettings& settings = {});

/// Writes the profile's shape as IGES (.igs/.iges, faces mode), STEP (.stp/.step, AP214) or
/// BRep (.brep), in `unit` ("MM", "CM", "M", "INCH" or "FT": the unit declared in the file,
/// lengths converted to it; BRep files are always mm). Returns true, or an error naming the path.
Expected<bool> write_profile_cad(const ProfileSpec& spec, const std::string& path,
                                 const std::string& unit = "MM");

/// Writes any loaded shape the same way (used by tests and `springscan model --convert`).
Expected<bool> write_cad(const CadShape& shape, const std::string& path,
                         const std::string& unit = "MM");

}  // namespace springscan::parts
