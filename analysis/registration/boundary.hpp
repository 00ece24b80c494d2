#pragma once
// The part's boundary in the global fit. The surface term of ICP cannot see a motion that slides
// the surface along itself: a profile along its length, a flat sheet in its plane. Those
// directions are not free for the part, whose ends are where the CAD says: when the scan spans
// the part from end to end along such a direction, its ends are matched to the model's ends;
// when it does not (only the middle of a long profile scanned), the direction stays free, and
// the result says so and by which rule it was fixed.
//
// Method, per free translation u (from the scan's surface information, sum of n n^T over scan
// points on the surface, eigenvalues below free_eigenvalue_ratio x the largest):
//   1. each end of the scan and of the model along u is estimated from the points in a band
//      of width end_band_mm at that end: for points spread evenly up to the end e, the band
//      [e0 - w, e] (e0 the outermost point) has mean (e0 - w + e) / 2, so e = 2 mean - e0 + w,
//      far less noisy than the outermost point alone; the model's points are even samples of its
//      tessellation, so both sides are estimated alike; on the model, faces that face along u
//      (a solid sheet's end faces, which a laser looking at the skins does not see) are left
//      out; the scan's points are all kept (leaving out those whose nearest sample faces along
//      u was tried: the motor bracket's shift 0.032 -> 0.002 mm, the side panel's 0.018 ->
//      0.075, the front panel's points-only field unchanged; not kept);
//   2. scan length within cover_tolerance_mm of the model's: the scan covers both ends, and the
//      fit moves along u by the difference of the two centres (pinned); shorter: free, left
//      where the surface fit put it; longer (extra material, a fixture): centred, said so.
//
// Thread safety: a pure function.

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include "analysis/core/expected.hpp"
#include "analysis/core/kdtree.hpp"
#include "analysis/core/part_model.hpp"
#include "analysis/core/point_cloud.hpp"

namespace springscan::analysis {

struct BoundarySettings {
  bool pin_free_directions = true;      ///< false: free directions are reported, not pinned
  double free_eigenvalue_ratio = 2e-2;  ///< translation information below this x the largest
  double end_band_mm = 1.0;             ///< width of the band that locates each end
  double surface_distance_mm = 0.3;     ///< scan points this close to the surface are used
  double cover_tolerance_mm = 1.0;      ///< lengths this close: the scan spans both ends
  double end_search_mm = 10.0;          ///< scan ends looked for this far from the model's
  std::size_t info_points = 20'000;     ///< scan points for the surface information
  std::size_t scan_points = 200'000;    ///< scan points (strided) for the end positions
  std::size_t model_points = 200'000;   ///< even samples of the tessellation for the model's
  std::size_t min_band_points = 20;     ///< fewer in an end band: that end is not located
  int threads = 0;                      ///< worker threads (0 = all cores); same result for any
};

/// A translation the scan's surface does not fix, and what the boundary made of it.
struct FreeDirection {
  Vec3 direction = Vec3::Zero();  ///< unit, CAD frame
  bool pinned = false;            ///< fixed by the part's ends
  double shift_mm = 0.0;          ///< the motion applied along `direction`
  double model_length_mm = 0.0;   ///< the model's extent along it (end to end)
  double scan_length_mm = 0.0;    ///< the scan's
  std::string rule;               ///< how the position along it was fixed, in words
};

struct BoundaryResult {
  Transform T_cad_scan = Transform::Identity();  ///< the fit with the pinned shifts applied
  std::vector<FreeDirection> free_directions;
};

/// The end of evenly spread `values` at their high side by the band estimate (step 1 above,
/// band `band_mm`), after leaving out the `skip_outermost` largest (stray points beyond the
/// end); nothing when the band holds fewer than `min_points`. `values` is reordered. Also the
/// datum alignment's edge points (registration/datum.hpp).
std::optional<double> high_end(std::vector<double>& values, double band_mm, std::size_t min_points,
                               std::size_t skip_outermost);

/// Pins the free translations of the fit `T_cad_scan` by the part's ends (see above). `scan` in
/// the scan frame; `model_tree` holds model.samples.points. Errors: empty scan or model,
/// settings out of range.
Expected<BoundaryResult> pin_to_boundary(const std::vector<Vec3>& scan, const Transform& T_cad_scan,
                                         const PartModel& model, const KdTree& model_tree,
                                         const BoundarySettings& settings = {});

/// What pin_to_boundary reads of a scan: its evenly strided samples (settings.info_points and,
/// built on first use, settings.scan_points) and the latter in space order. Prepared once, it
/// serves every pin of the same scan with the same settings (the pipeline pins the global fit,
/// each rival orientation and the least-squares finish: 3 samples of a 1M scan and their space
/// order, ~15 ms, were drawn anew each time) with the same results. Holds a reference to `scan`,
/// which must outlive it. Not for concurrent pins (the large sample is built lazily).
class BoundaryScan {
 public:
  BoundaryScan(const std::vector<Vec3>& scan, const BoundarySettings& settings);
  const std::vector<Vec3>& scan() const { return *scan_; }
  /// True when built with `settings`' sample counts and threads.
  bool fits(const BoundarySettings& settings) const;
  const std::vector<Vec3>& info() const { return info_; }
  /// strided_sample(scan, settings.scan_points) gathered in search order, with each point's
  /// index in that sample.
  const std::vector<Vec3>& ordered() const;
  const std::vector<std::uint32_t>& index() const;

 private:
  void build() const;
  const std::vector<Vec3>* scan_;
  std::size_t info_points_;
  std::size_t scan_points_;
  int threads_;
  std::vector<Vec3> info_;
  mutable std::vector<Vec3> ordered_;
  mutable std::vector<std::uint32_t> index_;
};

/// pin_to_boundary on a prepared scan; one prepared with other sample counts is drawn anew.
Expected<BoundaryResult> pin_to_boundary(const BoundaryScan& scan, const Transform& T_cad_scan,
                                         const PartModel& model, const KdTree& model_tree,
                                         const BoundarySettings& settings = {});

}  // namespace springscan::analysis
