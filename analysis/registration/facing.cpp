#include "analysis/registration/facing.hpp"

#include <array>
#include <cmath>
#include <functional>
#include <limits>
#include <queue>

#include "analysis/core/parallel.hpp"
#include "analysis/preprocess/normals.hpp"
#include "analysis/preprocess/voxel.hpp"

namespace springscan::analysis {

std::optional<Neighbor> nearest_facing(const KdTree& tree, const std::vector<Vec3>& normals,
                                       const Vec3& query, const Vec3& normal,
                                       double max_distance_mm, double min_dot) {
  if (normal.isZero()) return tree.nearest(query, max_distance_mm);
  return tree.nearest_along(query, normals, normal, max_distance_mm, kFacingRank, min_dot);
}

double facing_squared_distance(const KdTree& tree, const std::vector<Vec3>& normals,
                               const Vec3& query, const Vec3& normal) {
  const auto hit =
      normal.isZero() ? tree.nearest(query) : tree.nearest_along(query, normals, normal);
  return hit ? hit->squared_distance : std::numeric_limits<double>::infinity();
}

IcpPairSearch nearest_facing_pairs(const KdTree& tree, const std::vector<Vec3>& normals,
                                   const std::vector<Vec3>& source_normals, double max_distance_mm,
                                   double min_dot) {
  const double limit =
      max_distance_mm > 0.0 ? max_distance_mm : std::numeric_limits<double>::infinity();
  return [&tree, &normals, &source_normals, limit, min_dot](
             const std::vector<Vec3>& source, const Transform& T, std::size_t begin,
             std::size_t end, std::vector<IcpPair>& pairs) {
    for (std::size_t i = begin; i < end; ++i) {
      const auto hit = nearest_facing(tree, normals, T * source[i], T.linear() * source_normals[i],
                                      limit, min_dot);
      IcpPair& p = pairs[i];
      p.valid = hit.has_value();
      if (!hit) continue;
      p.point = tree.points()[hit->index];
      p.normal = normals[hit->index];
      p.squared_distance_mm2 = hit->squared_distance;
    }
  };
}

IcpPairSearch exact_surface_pairs(const SurfaceDistance& exact,
                                  const std::vector<Vec3>& source_normals, double max_distance_mm) {
  const double limit2 = max_distance_mm > 0.0 ? max_distance_mm * max_distance_mm
                                              : std::numeric_limits<double>::infinity();
  return [&exact, &source_normals, limit2](const std::vector<Vec3>& source, const Transform& T,
                                           std::size_t begin, std::size_t end,
                                           std::vector<IcpPair>& pairs) {
    for (std::size_t i = begin; i < end; ++i) {
      const Vec3 q = T * source[i];
      const SurfaceHit hit = exact.closest(q);
      IcpPair& p = pairs[i];
      p.point = hit.foot;
      p.normal = hit.normal;
      p.squared_distance_mm2 = (q - hit.foot).squaredNorm();
      const Vec3 n = source_normals.empty() ? Vec3::Zero() : Vec3(T.linear() * source_normals[i]);
      p.valid = std::isfinite(hit.signed_distance_mm) && p.squared_distance_mm2 <= limit2 &&
                (n.isZero() || hit.normal.dot(n) > 0.0);
    }
  };
}

namespace {

// How many nearest points a skin grows to from each point, the point itself included (as the
// normals' estimate, preprocess/normals.hpp).
constexpr std::size_t kSkinNeighbours = 10;
// A seed faces the viewpoint within 45 deg. A pass tilted 35 deg sees a skin that faces up to
// 125 deg away from the viewpoint (grazing), and its estimated normal, turned toward the
// viewpoint, then faces it within 55 deg with the wrong sign: with seeds at 60 deg, one such
// point on a bend's outer skin turned a whole wall (a perfect Z profile 1.2 mm off).
constexpr double kMinFacingViewpoint = 0.70710678118654752;  // cos 45 deg
constexpr double kMinParallel = 0.5;                         // a step between normals within 60 deg
// A seed that grows first lies on a flat patch of one skin: every one of its neighbours' normals
// within 30 deg of its own. Where a wall is seen on both skins by sparse grazing lines, a point's
// neighbours span the sheet and its plane may be one across it, whose normal lies in the wall and
// may face the viewpoint: such seeds signed a points-only Z profile's walls at random (1,325 of
// 9,514 fit points wrong, its frame 1.40 mm off; 5 wrong and 0.08 mm with this rule).
constexpr double kMinFlatSeed = 0.86602540378443865;  // cos 30 deg

// Every point's kSkinNeighbours nearest (itself included), found once for the normals' estimate
// and the growth: point i's are index[i * kSkinNeighbours, + count[i]).
struct NeighbourGraph {
  std::vector<std::uint32_t> index;
  std::vector<std::uint8_t> count;

  const std::uint32_t* of(std::size_t i) const { return index.data() + i * kSkinNeighbours; }
};

NeighbourGraph nearest_neighbours(const KdTree& tree, int threads) {
  const std::size_t n = tree.size();
  NeighbourGraph g{std::vector<std::uint32_t>(n * kSkinNeighbours), std::vector<std::uint8_t>(n)};
  parallel_blocks(n, threads, [&](std::size_t, std::size_t begin, std::size_t end) {
    std::array<double, kSkinNeighbours> d2{};
    for (std::size_t i = begin; i < end; ++i)
      g.count[i] = static_cast<std::uint8_t>(tree.knn(
          tree.points()[i], kSkinNeighbours, g.index.data() + i * kSkinNeighbours, d2.data()));
  });
  return g;
}

// A step of the growth: to point `to` from an oriented point, at cost 1 - |n_from . n_to|.
struct SkinStep {
  double cost;
  std::uint32_t from, to;
  bool operator>(const SkinStep& o) const { return cost > o.cost; }
};

// orient_along_skins over a neighbour graph of `points`.
SkinNormals grow_along_skins(const std::vector<Vec3>& points, const std::vector<Vec3>& normals,
                             const NeighbourGraph& graph, const Vec3& viewpoint,
                             double max_off_skin_mm) {
  SkinNormals out{normals, std::vector<std::uint8_t>(points.size(), 0)};
  std::priority_queue<SkinStep, std::vector<SkinStep>, std::greater<>> steps;
  const auto push_neighbours = [&](std::uint32_t i) {
    const Vec3& p = points[i];
    const Vec3& n = out.normals[i];
    const std::uint32_t* nn = graph.of(i);
    for (std::size_t j = 0; j < graph.count[i]; ++j) {
      const std::uint32_t q = nn[j];
      const Vec3& m = out.normals[q];
      if (out.known[q] || m.isZero()) continue;
      const Vec3 d = points[q] - p;
      const double parallel = std::abs(n.dot(m));
      // The other skin lies off this one's tangent plane by a sheet thickness.
      if (parallel < kMinParallel || std::abs(n.dot(d)) > max_off_skin_mm ||
          std::abs(m.dot(d)) > max_off_skin_mm)
        continue;
      steps.push({1.0 - parallel, i, q});
    }
  };
  const auto neighbours_within = [&](std::size_t i, double min_dot) {
    const std::uint32_t* nn = graph.of(i);
    for (std::size_t j = 0; j < graph.count[i]; ++j)
      if (std::abs(normals[nn[j]].dot(normals[i])) < min_dot) return false;
    return true;
  };
  // Prim's order from every seed at once: each point takes its sign over the most parallel step
  // that reaches it first.
  const auto grow = [&] {
    while (!steps.empty()) {
      const SkinStep s = steps.top();
      steps.pop();
      if (out.known[s.to]) continue;
      Vec3& m = out.normals[s.to];
      if (out.normals[s.from].dot(m) < 0.0) m = -m;
      out.known[s.to] = 1;
      push_neighbours(s.to);
    }
  };
  std::vector<std::uint32_t> facing;
  for (std::size_t i = 0; i < points.size(); ++i) {
    const Vec3& n = normals[i];
    if (n.isZero() || n.dot((viewpoint - points[i]).normalized()) < kMinFacingViewpoint) continue;
    facing.push_back(static_cast<std::uint32_t>(i));
  }
  // The seeds on flat patches grow first. Then the facing points they did not reach whose
  // neighbours' normals lie within 60 deg seed what is left: without them a wall skin that no flat
  // seed's growth reached stayed unknown and out of the last least squares (a points-only Z
  // profile 0.019 -> 0.074 mm). A point whose neighbours' normals spread wider seeds nothing.
  for (const double min_dot : {kMinFlatSeed, kMinParallel}) {
    for (const std::uint32_t i : facing) {
      if (out.known[i] || !neighbours_within(i, min_dot)) continue;
      out.known[i] = 1;
      push_neighbours(i);
    }
    grow();
  }
  return out;
}

// The least-squares plane normal of every point of `points` over its graph neighbours, turned
// toward `viewpoint` (preprocess/normals.hpp estimate_normals, on the neighbours found once).
std::vector<Vec3> graph_normals(const std::vector<Vec3>& points, const NeighbourGraph& graph,
                                const Vec3& viewpoint, int threads) {
  std::vector<Vec3> normals(points.size(), Vec3::Zero());
  parallel_blocks(points.size(), threads, [&](std::size_t, std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      Vec3 n;
      double variation = 0.0;
      if (!fit_plane(points, graph.of(i), graph.count[i], n, variation)) continue;
      normals[i] = n.dot(viewpoint - points[i]) < 0.0 ? Vec3(-n) : n;
    }
  });
  return normals;
}

// The sign of fit point `p`'s normal `n` that the signed fine points within `radius_mm` agree
// on: +1 or -1, 0 when none is parallel to it or they disagree (both skins near it).
int agreed_sign(const KdTree& fine_tree, const SkinNormals& fine, const Vec3& p, const Vec3& n,
                double radius_mm, std::vector<Neighbor>& near) {
  fine_tree.radius(p, radius_mm, near);
  bool along = false, against = false;
  for (const Neighbor& nb : near) {
    if (!fine.known[nb.index]) continue;
    const double c = fine.normals[nb.index].dot(n);
    along = along || c >= kMinParallel;
    against = against || c <= -kMinParallel;
  }
  return along == against ? 0 : (along ? 1 : -1);
}

}  // namespace

SkinNormals orient_along_skins(const std::vector<Vec3>& points, const std::vector<Vec3>& normals,
                               const Vec3& viewpoint, double max_off_skin_mm) {
  if (points.empty() || normals.size() != points.size())
    return SkinNormals{normals, std::vector<std::uint8_t>(points.size(), 0)};
  const KdTree tree(points);
  return grow_along_skins(points, normals, nearest_neighbours(tree, 1), viewpoint, max_off_skin_mm);
}

SkinNormals orient_fit_points_along_skins(const std::vector<Vec3>& scan_points,
                                          const std::vector<Vec3>& fit_points,
                                          const std::vector<Vec3>& fit_normals, double fit_voxel_mm,
                                          const Vec3& viewpoint, double thickness_mm, int threads) {
  const double half_sheet = 0.5 * thickness_mm;
  if (!(fit_voxel_mm > half_sheet))
    return orient_along_skins(fit_points, fit_normals, viewpoint, half_sheet);
  SkinNormals out{fit_normals, std::vector<std::uint8_t>(fit_points.size(), 0)};
  if (fit_points.empty() || fit_normals.size() != fit_points.size()) return out;
  // The fine sample: one centroid per cube of half the sheet, whose diagonal (0.87 of the sheet)
  // cannot reach from one skin to the other; of the whole scan (of a strided half, the front
  // panel's frame was 0.23 mm off again: sparser cubes, noisier normals).
  // A scan denser than kFineSampleInput is thinned by a stride first: the sample's cost grows
  // with its input (1M side panel points took 1.6 s here, 0.2 s at 200k), and 250k points already
  // fill the half-sheet cubes of a production part; no scan up to that size changes.
  constexpr std::size_t kFineSampleInput = 250'000;
  const std::size_t stride = (scan_points.size() + kFineSampleInput - 1) / kFineSampleInput;
  PointCloud scan;
  scan.points.reserve(scan_points.size() / stride + 1);
  for (std::size_t i = 0; i < scan_points.size(); i += stride)
    scan.points.push_back(scan_points[i]);
  auto fine = voxel_reduce(scan, VoxelSettings{half_sheet});
  if (!fine) return out;
  const std::vector<Vec3>& points = fine->cloud.points;
  const KdTree fine_tree(points);
  const NeighbourGraph graph = nearest_neighbours(fine_tree, threads);
  const SkinNormals signed_fine = grow_along_skins(
      points, graph_normals(points, graph, viewpoint, threads), graph, viewpoint, half_sheet);
  std::vector<Neighbor> near;
  for (std::size_t i = 0; i < fit_points.size(); ++i) {
    if (fit_normals[i].isZero()) continue;
    const int sign = agreed_sign(fine_tree, signed_fine, fit_points[i], fit_normals[i],
                                 0.5 * fit_voxel_mm, near);
    if (sign == 0) continue;
    out.known[i] = 1;
    if (sign < 0) out.normals[i] = -fit_normals[i];
  }
  return out;
}

}  // namespace springscan::analysis
