#include "analysis/core/triangle_bvh.hpp"

#include <algorithm>
#include <limits>

namespace springscan::analysis {

TriangleFoot closest_on_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  // Voronoi regions of the vertices, edges and face, in that order (Ericson 5.1.5).
  TriangleFoot foot;
  const auto done = [&](double wa, double wb, double wc) {
    foot.barycentric = Vec3(wa, wb, wc);
    foot.point = wa * a + wb * b + wc * c;
    foot.squared_distance = (p - foot.point).squaredNorm();
    return foot;
  };
  const Vec3 ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0.0 && d2 <= 0.0) return done(1, 0, 0);
  const Vec3 bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0.0 && d4 <= d3) return done(0, 1, 0);
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) {
    const double v = d1 / (d1 - d3);
    return done(1 - v, v, 0);
  }
  const Vec3 cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0.0 && d5 <= d6) return done(0, 0, 1);
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) {
    const double w = d2 / (d2 - d6);
    return done(1 - w, 0, w);
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0) {
    const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    return done(0, 1 - w, w);
  }
  const double sum = va + vb + vc;
  if (!(std::abs(sum) > 0.0)) return done(1, 0, 0);  // degenerate triangle: its first vertex
  const double v = vb / sum, w = vc / sum;
  return done(1 - v - w, v, w);
}

TriangleBvh::TriangleBvh(const std::vector<Vec3>& vertices,
                         const std::vector<std::array<std::uint32_t, 3>>& triangles,
                         const TriangleBvhSettings& settings) {
  corners_.reserve(triangles.size());
  original_.reserve(triangles.size());
  for (std::size_t i = 0; i < triangles.size(); ++i) {
    const auto& t = triangles[i];
    corners_.push_back({vertices[t[0]], vertices[t[1]], vertices[t[2]]});
    original_.push_back(static_cast<std::uint32_t>(i));
  }
  if (corners_.empty()) return;
  nodes_.reserve(2 * corners_.size() + 1);
  nodes_.emplace_back();
  build(0, 0, static_cast<std::uint32_t>(corners_.size()), std::clamp(settings.leaf_size, 1, 64));
  boxes_.reserve(corners_.size());
  for (const auto& t : corners_)
    boxes_.push_back({t[0].cwiseMin(t[1]).cwiseMin(t[2]), t[0].cwiseMax(t[1]).cwiseMax(t[2])});
  leaf_of_.resize(corners_.size());
  for (std::uint32_t n = 0; n < nodes_.size(); ++n)
    for (std::uint32_t i = 0; i < nodes_[n].count; ++i) leaf_of_[nodes_[n].first + i] = n;
}

// Median split along the longest axis of the centroids' box; node 0 is the root and each inner
// node's two children are adjacent. Depth stays near log2(n / leaf), well inside the query stack.
void TriangleBvh::build(std::uint32_t node, std::uint32_t first, std::uint32_t count,
                        int leaf_size) {
  Vec3 lo = Vec3::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  Vec3 clo = lo, chi = hi;
  for (std::uint32_t i = first; i < first + count; ++i) {
    for (const Vec3& v : corners_[i]) lo = lo.cwiseMin(v), hi = hi.cwiseMax(v);
    const Vec3 centroid = (corners_[i][0] + corners_[i][1] + corners_[i][2]) / 3.0;
    clo = clo.cwiseMin(centroid), chi = chi.cwiseMax(centroid);
  }
  nodes_[node].lo = lo;
  nodes_[node].hi = hi;
  if (count <= static_cast<std::uint32_t>(leaf_size)) {
    nodes_[node].first = first;
    nodes_[node].count = count;
    return;
  }
  int axis = 0;
  (chi - clo).maxCoeff(&axis);
  const std::uint32_t half = count / 2;
  std::vector<std::uint32_t> order(count);
  for (std::uint32_t i = 0; i < count; ++i) order[i] = first + i;
  const auto key = [&](std::uint32_t i) {
    return corners_[i][0][axis] + corners_[i][1][axis] + corners_[i][2][axis];
  };
  std::nth_element(order.begin(), order.begin() + half, order.end(),
                   [&](std::uint32_t a, std::uint32_t b) { return key(a) < key(b); });
  std::vector<std::array<Vec3, 3>> corners(count);
  std::vector<std::uint32_t> original(count);
  for (std::uint32_t i = 0; i < count; ++i) {
    corners[i] = corners_[order[i]];
    original[i] = original_[order[i]];
  }
  std::copy(corners.begin(), corners.end(), corners_.begin() + first);
  std::copy(original.begin(), original.end(), original_.begin() + first);
  const auto left = static_cast<std::uint32_t>(nodes_.size());
  nodes_.emplace_back();
  nodes_.emplace_back();
  nodes_[node].first = left;
  nodes_[node].count = 0;
  nodes_[left].parent = nodes_[left + 1].parent = node;
  build(left, first, half, leaf_size);
  build(left + 1, first + half, count - half, leaf_size);
}

}  // namespace springscan::analysis
