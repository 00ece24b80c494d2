// Exact point-to-CAD distance: BVH candidates over the tessellation, refined per face on the
// true surface (cad_distance_faces.cpp). The steps are listed in cad_distance.hpp.
#include "analysis/cad/distance.hpp"

#include <Standard_Failure.hxx>
#include <algorithm>
#include <limits>

#include "analysis/cad/distance_internal.hpp"
#include "analysis/core/parallel.hpp"

namespace springscan::analysis {
namespace {

// Faces kept per query; more than this many faces within the slack of the nearest triangle is
// only possible on degenerate models, and the nearest ones are kept.
constexpr int kMaxCandidates = 32;

// The nearest triangle of a thread's last query (closest_within).
struct LastHit {
  const void* owner = nullptr;  // the CadDistance that answered; only compared
  std::uint32_t slot = 0;       // TriangleFoot::slot of its nearest triangle
};

struct Candidate {
  int face = -1;
  TriangleFoot foot;
  double distance() const { return std::sqrt(foot.squared_distance); }
};

class CadDistance final : public SurfaceDistance {
 public:
  CadDistance(CadShape shape, const CadDistanceSettings& settings)
      : shape_(std::move(shape)),
        tables_(build_distance_tables(shape_.impl(), settings.candidate_margin_mm)),
        bvh_(shape_.mesh().vertices, shape_.mesh().triangles,
             TriangleBvhSettings{settings.bvh_leaf_size}) {
    for (const auto& face : tables_.faces) max_slack_ = std::max(max_slack_, face.slack_mm);
  }

  SurfaceHit closest(const Vec3& query) const override {
    return closest_within(query, std::numeric_limits<double>::infinity());
  }

  SurfaceHit closest_within(const Vec3& query, double bound_mm) const override {
    // A surface point within bound_mm puts the nearest triangle within bound_mm + its slack.
    const double mesh_bound = bound_mm + max_slack_;
    // A run of queries along a scan line (closest_in_order) has its nearest triangles side by
    // side: the search starts in the leaf of this thread's previous nearest triangle on this
    // model (any start gives the same answer; this one is fast).
    thread_local LastHit last;
    const std::uint32_t start = last.owner == this ? last.slot : ~std::uint32_t{0};
    // Reused per thread: a fresh array of kMaxCandidates feet per query, value-initialised,
    // cost more than the search when the hit is the one triangle under the point.
    thread_local std::vector<Candidate> candidates;
    candidates.resize(kMaxCandidates);
    int count = 0;
    const auto& faces = shape_.mesh().triangle_faces;
    const double nearest = bvh_.near_from(
        start, query, max_slack_,
        [&](const TriangleFoot& foot) {
          const int face = faces[foot.triangle];
          int worst = 0;
          for (int i = 0; i < count; ++i) {
            if (candidates[i].face == face) {
              if (foot.squared_distance < candidates[i].foot.squared_distance)
                candidates[i].foot = foot;
              return;
            }
            if (candidates[i].foot.squared_distance > candidates[worst].foot.squared_distance)
              worst = i;
          }
          if (count < kMaxCandidates) {
            candidates[count++] = {face, foot};
          } else if (foot.squared_distance < candidates[worst].foot.squared_distance) {
            candidates[worst] = {face, foot};
          }
        },
        mesh_bound);
    // Ties by face: at an edge two faces are equally near, and the order in which the search
    // met them (which its bound changes) must not decide which face the hit names.
    std::sort(candidates.begin(), candidates.begin() + count,
              [](const Candidate& a, const Candidate& b) {
                return a.foot.squared_distance < b.foot.squared_distance ||
                       (a.foot.squared_distance == b.foot.squared_distance && a.face < b.face);
              });
    SurfaceHit hit;
    hit.signed_distance_mm = std::numeric_limits<double>::infinity();
    double best = std::numeric_limits<double>::infinity();
    for (int i = 0; i < count; ++i) {
      const Candidate& c = candidates[i];
      const double slack = tables_.faces[static_cast<std::size_t>(c.face)].slack_mm;
      // Mesh and surface differ by at most the slack: skip faces that cannot be closer.
      if (c.distance() > nearest + slack || c.distance() - slack >= best) continue;
      const FaceFoot foot = refine(c, query);
      if (!foot.valid || foot.distance >= best) continue;
      best = foot.distance;
      hit.foot = foot.point;
      hit.normal = foot.normal;
      hit.face_id = c.face;
      last = {this, c.foot.slot};
      // The sign of the side the outward normal points to; on the surface itself, +0.
      hit.signed_distance_mm = (query - foot.point).dot(foot.normal) < 0.0 ? -best : best;
    }
    return hit;
  }

 private:
  // The exact foot on the candidate's face; should OpenCASCADE fail on a degenerate face, the
  // triangle's own closest point stands in (off by at most the face's deflection).
  FaceFoot refine(const Candidate& c, const Vec3& query) const {
    try {
      return foot_on_face(shape_.impl(), tables_, c.face, query, c.foot);
    } catch (const Standard_Failure&) {
      const auto& tri = shape_.mesh().triangles[c.foot.triangle];
      const auto& v = shape_.mesh().vertices;
      return {true, c.foot.point, (v[tri[1]] - v[tri[0]]).cross(v[tri[2]] - v[tri[0]]).normalized(),
              c.distance()};
    }
  }

  CadShape shape_;
  DistanceTables tables_;
  TriangleBvh bvh_;
  double max_slack_ = 0.0;
};

}  // namespace

std::shared_ptr<const SurfaceDistance> make_cad_distance(const CadShape& shape,
                                                         const CadDistanceSettings& settings) {
  if (shape.empty()) return nullptr;
  return std::make_shared<CadDistance>(shape, settings);
}

std::vector<SurfaceHit> closest_all(const SurfaceDistance& distance,
                                    const std::vector<Vec3>& points, int threads) {
  std::vector<SurfaceHit> hits(points.size());
  parallel_blocks(points.size(), threads, [&](std::size_t, std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) hits[i] = distance.closest(points[i]);
  });
  return hits;
}

}  // namespace springscan::analysis
