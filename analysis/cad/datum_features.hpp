#pragma once
// Candidate datum features of a CAD part (docs/alignment.md "Datum alignment"): what a quality
// engineer picks the datum list from (`springscan model PART --json`, "datum_candidates").
//  - planar pads: the flanges, largest first, each with a point on its material and its normal;
//  - round holes: concave cylinder groups (one axis, one radius, not a bend) through a flange,
//    their arcs closing the full circle; centre on the flange's skin, axis its normal;
//  - slots: two such groups of one radius, each a half circle (its arc turned away from the
//    other), on parallel axes through the same flange; centre midway on the flange's skin,
//    `direction` across the slot (what a slot datum fixes), width 2 r, length the axes' distance
//    + 2 r.
// Edge points are not listed: which edge locates the part is the engineer's choice.
//
// Thread safety: pure functions.

#include <vector>

#include "analysis/cad/import.hpp"
#include "analysis/cad/segmentation.hpp"
#include "analysis/core/part_model.hpp"

namespace springscan::analysis {

struct PadCandidate {
  int flange_id = 0;
  Vec3 point = Vec3::Zero();    ///< on the material of the flange's skin (largest face's largest
                                ///< triangle), CAD frame
  Vec3 normal = Vec3::UnitZ();  ///< the flange's normal (out of the material on that skin)
  double area_mm2 = 0.0;        ///< the flange's
  double thickness_mm = 0.0;    ///< 0 for a surface model
};

struct HoleCandidate {
  std::vector<int> face_ids;   ///< the hole's cylinder faces
  int flange_id = 0;           ///< the flange it goes through
  Vec3 centre = Vec3::Zero();  ///< on the axis, in the plane of the flange's point and normal
  Vec3 axis = Vec3::UnitZ();   ///< unit, along the flange's normal
  double diameter_mm = 0.0;
  double thickness_mm = 0.0;  ///< the flange's (the wall's height)
};

struct SlotCandidate {
  std::vector<int> face_ids;       ///< the two round ends' cylinder faces
  int flange_id = 0;               ///< the flange it goes through
  Vec3 centre = Vec3::Zero();      ///< midway between the ends' axes, on the flange's skin
  Vec3 axis = Vec3::UnitZ();       ///< unit, along the flange's normal
  Vec3 direction = Vec3::UnitX();  ///< unit, across the slot (in the flange's plane)
  double width_mm = 0.0;           ///< 2 r (a slot datum's diameter_mm)
  double length_mm = 0.0;          ///< end to end
  double thickness_mm = 0.0;       ///< the flange's (the walls' height)
};

struct DatumCandidates {
  std::vector<PadCandidate> pads;    ///< by area, largest first
  std::vector<HoleCandidate> holes;  ///< by diameter, largest first
  std::vector<SlotCandidate> slots;  ///< by length, longest first
};

struct DatumCandidateSettings {
  double parallel_deg = 0.5;       ///< hole axis within this of the flange's normal
  double coaxial_mm = 0.05;        ///< cylinder faces this close on one axis are one hole
  double same_radius_mm = 0.02;    ///< ... with radii this close
  double full_circle_deg = 350.0;  ///< a hole's faces sweep at least this much (not a notch)
  double half_circle_tolerance_deg = 10.0;  ///< a slot's end sweeps 180 deg within this
};

/// The candidates of `shape` with its face descriptions and segmentation (describe_faces,
/// segment_cad). A surface model has no hole walls: it lists pads only.
DatumCandidates datum_candidates(const CadShape& shape, const std::vector<CadFaceInfo>& faces,
                                 const PartSegmentation& segmentation,
                                 const DatumCandidateSettings& settings = {});

}  // namespace springscan::analysis
