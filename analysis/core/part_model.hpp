#pragma once
// A CAD part as the analysis sees it: even surface samples, the segmentation into flanges and
// bends, and exact distance queries. No OpenCASCADE type appears here: analysis/cad_*.cpp
// builds a PartModel from IGES/STEP, tests and simulators build one from synthetic geometry.

#include <cmath>
#include <cstddef>
#include <memory>
#include <mutex>
#include <string>
#include <utility>
#include <vector>

#include "analysis/core/point_cloud.hpp"

namespace springscan::analysis {

/// A flat region of the sheet: adjacent coplanar CAD faces merged (DESIGN.md stage 6-7).
struct Flange {
  int id = 0;
  std::vector<int> face_ids;
  Vec3 point = Vec3::Zero();    ///< a point on the plane (CAD frame, mm)
  Vec3 normal = Vec3::UnitZ();  ///< unit plane normal, along the faces' outward orientation
  double area_mm2 = 0.0;
  /// Distance between the sheet's two sides when the flange has both (a solid); 0 for a
  /// surface model. `point` and `normal` are those of one side: which one, a bend's geometry
  /// tells (springback.cpp, concave_normal).
  double thickness_mm = 0.0;
};

/// A bend: a cylindrical (or tangent-continuous curved) region joining two flanges.
struct Bend {
  int id = 0;
  std::vector<int> face_ids;
  Vec3 axis_point = Vec3::Zero();
  Vec3 axis_direction = Vec3::UnitX();  ///< unit
  double radius_mm = 0.0;               ///< inner bend radius
  double nominal_angle_deg = 0.0;       ///< the angle the sheet turns at the bend (0 = flat)
  int flange_a = -1;                    ///< Flange::id on one side
  int flange_b = -1;                    ///< Flange::id on the other side
};

struct PartSegmentation {
  std::vector<Flange> flanges;
  std::vector<Bend> bends;
  std::vector<int> other_faces;  ///< faces that are neither flange nor bend
};

/// The closest point of the model surface to a query point.
struct SurfaceHit {
  double signed_distance_mm = 0.0;  ///< positive on the side the surface normal points to
  Vec3 foot = Vec3::Zero();         ///< closest surface point
  Vec3 normal = Vec3::UnitZ();      ///< surface normal at the foot
  int face_id = -1;
};

/// Exact point-to-surface distance. Implementations must allow concurrent calls to `closest`.
class SurfaceDistance {
 public:
  virtual ~SurfaceDistance() = default;
  /// The closest surface point to `query` (CAD frame, mm).
  virtual SurfaceHit closest(const Vec3& query) const = 0;
  /// closest(query), told that the surface has a point within `bound_mm` of the query (for a
  /// run of neighbouring queries: the distance to the previous one's foot), which lets an
  /// implementation prune its search from the start. The answer is the same.
  virtual SurfaceHit closest_within(const Vec3& query, double bound_mm) const {
    (void)bound_mm;
    return closest(query);
  }
};

/// For i in [begin, end): out(i, closest(query(i))), each query told the distance to the previous
/// one's foot as its bound (SurfaceDistance::closest_within). A scan comes line by line, so that
/// bound is tight and prunes the search; the answers are those of closest().
template <typename Query, typename Out>
void closest_in_order(const SurfaceDistance& distance, std::size_t begin, std::size_t end,
                      Query&& query, Out&& out) {
  Vec3 previous_foot = Vec3::Zero();
  bool have_foot = false;
  for (std::size_t i = begin; i < end; ++i) {
    const Vec3 q = query(i);
    const SurfaceHit hit =
        have_foot ? distance.closest_within(q, (q - previous_foot).norm()) : distance.closest(q);
    out(i, hit);
    have_foot = std::isfinite(hit.signed_distance_mm);
    previous_foot = hit.foot;
  }
}

/// Point sets derived from a model, built on first use and kept with it: the global fit's
/// boundary pass samples the tessellation 200,000 times (registration/boundary.cpp), and built
/// on every call that was a tenth of the fit, on one thread, for the same points each time. A
/// station analyses one model many times. Safe to use from several threads (a second caller
/// waits for the first one's build). A copy starts empty (what it was derived from may then be
/// changed in the copy); a model's mesh and samples are not changed once it is in use.
class DerivedSamples {
 public:
  DerivedSamples() = default;
  DerivedSamples(const DerivedSamples&) {}
  DerivedSamples& operator=(const DerivedSamples&) {
    const std::lock_guard<std::mutex> lock(mutex_);
    entries_.clear();
    return *this;
  }

  /// The cloud kept under `key`, or build() kept under it.
  template <typename Build>
  std::shared_ptr<const PointCloud> get(std::size_t key, Build&& build) const {
    const std::lock_guard<std::mutex> lock(mutex_);
    for (const auto& [k, cloud] : entries_)
      if (k == key) return cloud;
    auto cloud = std::make_shared<const PointCloud>(build());
    entries_.emplace_back(key, cloud);
    return cloud;
  }

 private:
  mutable std::mutex mutex_;
  mutable std::vector<std::pair<std::size_t, std::shared_ptr<const PointCloud>>> entries_;
};

/// Everything the pipeline needs of the CAD side.
struct PartModel {
  PointCloud samples;  ///< even samples with normals and face ids
  PartSegmentation segmentation;
  int face_count = 0;
  std::shared_ptr<const SurfaceDistance> distance;  ///< null: distances to the samples instead
  /// The CAD tessellation (CAD frame, mm): the surface the compensated-surface.stl moves. Empty
  /// for a model built from points.
  TriangleMesh mesh;
  std::string source_sha256;  ///< hex SHA-256 of the file the model was built from (the report's
                              ///< input.cad_sha256: which CAD revision was measured against);
                              ///< empty for a model built in memory
  /// Even samples of `mesh` with their triangles' normals, by sample count (the boundary's).
  DerivedSamples tessellation_samples;
};

}  // namespace springscan::analysis
