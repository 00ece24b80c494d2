#include "analysis/registration/facing.hpp"

#include <cmath>
#include <limits>

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

}  // namespace springscan::analysis
