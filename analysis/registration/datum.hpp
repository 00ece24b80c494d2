#pragma once
// Datum (RPS) alignment (docs/alignment.md "3. Datum alignment"). A press shop judges a part in
// the frame of its datums, the reference points it is located by in the fixture, not in the
// best fit of the whole surface, which spreads the springback over the part. The part's config
// names datum features on the CAD, each fixing some directions:
//   - a plane pad (point, normal, radius) fixes the normal direction at its point;
//   - a round hole (centre, axis, diameter) fixes both directions across its axis, or one when
//     `direction` is given (a 2-way pin);
//   - a slot (centre, axis, width, length, the direction across it) fixes that direction;
//   - an edge point (point on the skin at the edge, skin normal, the direction out of the
//     material across the edge) fixes that direction.
// 3-2-1 (three pads, a hole, a 2-way hole or slot) fixes each of the six directions once; more
// datums (N-point) are solved as a weighted least-squares fit of all of them.
//
// Method, starting from the best fit T_cad_scan (global fit and boundary pinning):
//   1. each datum's feature is measured in the scan: a pad by a plane fit of the scan points on
//      the pad's skin within its radius; a hole by a circle fit (geometric, started from the
//      algebraic one, robust: points beyond outlier_sigmas robust sigmas left out) of the points
//      on its wall, across the nominal axis, which a tilted laser sees on the side facing it; a
//      slot by a stadium fit of its whole outline (straight edges and round ends) the same way;
//      an edge by its end face where seen, else by the band estimate of the skin's end across
//      it (registration/boundary.hpp step 1);
//   2. the datum frame: the rigid motion that brings every measured feature onto its nominal
//      position along the directions it fixes, weighted least squares (Gauss-Newton on exact
//      rotations); exact for 3-2-1;
//   3. steps 1-2 again in the datum frame with the narrow band (the best fit may be a few tenths
//      of a millimetre off at a datum), until the frame moves less than 1e-4 mm.
// Before them, capture rounds (datum_capture.cpp): springback elsewhere pulls the best fit up
// to several millimetres and degrees off at the datums, so each feature is first found within
// capture_mm (a pad by the dominant skin facing it, a hole or slot by where its outline fits the
// empty part of the skin's occupancy, then its rim) and the frame solved from those.
// A hole or slot is measured by what the scan shows: its wall, its rim on the seen skin, or both.
// When a datum cannot be measured from the best fit, the whole alignment is tried from the best
// fit turned half round about each of the part's principal axes (a near-symmetric part's best
// fit may lie turned so); one from which every datum is measured is the result when the scan
// contradicts a datum at the other half at the same pose (a pad's skin facing away, skin inside a
// hole's outline) and the surface does not favour that half, or when the whole surface fits it
// better than the other half (a part whose halves both carry the datum features, or whose datum
// is only out of the scan, is not turned on its datums alone).
// A datum whose feature cannot be measured (not in the scan, on the skin it does not see) is
// never a silent fallback to the best fit: the result says so (`achieved` false, the datum named
// and why), its frame the best fit, and the caller fails the verdict.
//
// Thread safety: pure functions.

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "analysis/core/expected.hpp"
#include "analysis/core/part_model.hpp"
#include "analysis/core/point_cloud.hpp"

namespace springscan::analysis {

enum class DatumKind : std::uint8_t { kPad, kHole, kSlot, kEdge };

/// "pad", "hole", "slot", "edge".
std::string to_string(DatumKind kind);

/// One datum feature, CAD frame, mm.
struct Datum {
  std::string name;  ///< unique, e.g. "A1" (the report and errors name it)
  DatumKind kind = DatumKind::kPad;
  Vec3 point = Vec3::Zero();      ///< pad: on the pad; hole, slot: the centre, on the skin
                                  ///< `normal` points out of; edge: on that skin at the edge
  Vec3 normal = Vec3::UnitZ();    ///< the skin's outward normal (pad normal, hole or slot axis)
  Vec3 direction = Vec3::Zero();  ///< across `normal`: hole: zero (both) or the one it fixes;
                                  ///< slot: across the slot; edge: out of the material
  double radius_mm = 5.0;         ///< pad: its radius; edge: half the length of edge used
  double diameter_mm = 0.0;       ///< hole: diameter; slot: width
  double length_mm = 0.0;         ///< slot: overall length (> width)
  double thickness_mm = 0.0;      ///< the wall's height; 0: the model's flange at `point`
  double weight = 1.0;            ///< > 0; relative, in the least-squares fit of the datums
};

struct DatumAlignmentSettings {
  std::vector<Datum> datums;  ///< empty: no datum alignment, the best fit is the result frame
  /// Capture rounds: each feature found up to this far off its nominal (and tilted up to 3 deg)
  /// where the best fit put it, by the dominant skin and the outline in it (a coarse solve);
  /// <= search_mm: none.
  double capture_mm = 5.0;
  double search_mm = 1.0;       ///< the pass after them: features looked for this far off
  double band_mm = 0.15;        ///< later passes, in the datum frame (noise and what is left)
  std::size_t min_points = 12;  ///< fewer scan points on a feature: not measurable
  double outlier_sigmas = 3.0;  ///< robust fits leave out points beyond this many sigmas
  int min_hole_sectors = 6;     ///< of 12 (30 deg each): a hole's wall seen over at least this
  int max_passes = 4;           ///< measure-and-solve rounds after the capture
  int max_capture_rounds = 2;   ///< capture rounds (ended when one moves less than search_mm / 2)
  int threads = 0;              ///< for the one pass over the scan; 0 = all cores
};

/// Errors name the field, the datum and the value: names (non-empty, unique), unit-izable
/// normals, directions across the normal, sizes and weights, and that the datums together fix
/// all six directions of a rigid motion (else which one is left free).
std::optional<Error> validate(const DatumAlignmentSettings& settings,
                              std::string_view context = "alignment: ");

/// One datum after the alignment.
struct DatumResult {
  Datum datum;                            ///< as configured (thickness resolved)
  Vec3 measured = Vec3::Zero();           ///< the feature's point in the result (datum) frame
  Vec3 measured_normal = Vec3::Zero();    ///< pads: the fitted plane's normal, result frame
  double measured_diameter_mm = 0.0;      ///< holes: diameter; slots: width
  Vec3 residual = Vec3::Zero();           ///< measured - nominal along the fixed directions
  Vec3 best_fit_residual = Vec3::Zero();  ///< the same in the best-fit frame
  int constraints = 0;                    ///< directions it fixes (1 or 2)
  std::size_t points = 0;                 ///< scan points the feature was fitted to
  double fit_rms_mm = 0.0;                ///< their rms distance from the fitted feature
  /// What of the feature the scan showed and the last round used: "plane" (pad), "wall", "rim"
  /// or "wall and rim" (hole, and a slot's whole outline: weighted by their centres'
  /// information), "end face" or "skin's end" (edge).
  std::string measured_by;
};

/// One measure-and-solve round.
struct DatumRound {
  std::string stage;      ///< "capture" (wide, coarse), "search" or "narrow" (datum_measure);
                          ///< "half turn" first: the start was the best fit turned half round
  double band_mm = 0.0;   ///< how far off the nominal a feature was looked for
  double moved_mm = 0.0;  ///< the frame's move by the round: its largest at a datum
  double moved_deg = 0.0;
};

struct DatumAlignmentResult {
  Transform T_cad_scan = Transform::Identity();    ///< the result frame
  Transform T_datum_best = Transform::Identity();  ///< the result frame from the best fit's
  std::vector<DatumResult> datums;                 ///< in the settings' order
  int passes = 0;                                  ///< rounds, the capture's included
  std::vector<DatumRound> rounds;
  /// False when a datum cannot be measured: T_cad_scan is then the best fit, `datums` empty,
  /// `failed_datum` names the datum and `failure` says why (the whole sentence).
  bool achieved = true;
  std::string failed_datum;
  std::string failure;
};

/// Measures every datum of `settings` in `scan` (scan frame; `scan_normals` one per point
/// toward the scanner, or empty) placed by the best fit `T_cad_scan_best`, and solves the datum
/// frame (steps above). `model` gives each hole's and slot's wall height (its flange's
/// thickness) when the datum does not. A datum not measurable: `achieved` false (above).
/// Errors: settings (validate), a slot without a wall height (a surface model's).
Expected<DatumAlignmentResult> align_to_datums(const std::vector<Vec3>& scan,
                                               const std::vector<Vec3>& scan_normals,
                                               const Transform& T_cad_scan_best,
                                               const PartModel& model,
                                               const DatumAlignmentSettings& settings);

}  // namespace springscan::analysis
