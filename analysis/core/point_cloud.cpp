#include "analysis/core/point_cloud.hpp"

namespace springscan::analysis {

PointCloud transformed(const PointCloud& cloud, const Transform& T) {
  PointCloud out = cloud;
  const Mat3 R = T.linear();
  for (auto& p : out.points) p = T * p;
  for (auto& n : out.normals) n = R * n;
  return out;
}

std::vector<Vec3> strided_sample(const std::vector<Vec3>& points, std::size_t count) {
  if (count == 0 || points.size() <= count) return points;
  const std::size_t stride = (points.size() + count - 1) / count;
  std::vector<Vec3> out;
  out.reserve(count);
  for (std::size_t block = 0, i = 0; i < points.size(); ++block, i += stride) {
    // splitmix64 of the block number: a fixed offset that no periodic order of the points
    // (scan lines of equal length, generated patterns) can line up with.
    std::uint64_t z = (block + 1) * 0x9E3779B97F4A7C15ull;
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    z ^= z >> 31;
    const std::size_t pick = i + static_cast<std::size_t>(z % stride);
    out.push_back(points[std::min(pick, points.size() - 1)]);
  }
  return out;
}

PointCloud select(const PointCloud& cloud, const std::vector<std::uint32_t>& indices) {
  PointCloud out;
  out.points.reserve(indices.size());
  for (auto i : indices) out.points.push_back(cloud.points[i]);
  if (cloud.has_normals()) {
    out.normals.reserve(indices.size());
    for (auto i : indices) out.normals.push_back(cloud.normals[i]);
  }
  if (cloud.has_scalars()) {
    out.scalars.reserve(indices.size());
    for (auto i : indices) out.scalars.push_back(cloud.scalars[i]);
  }
  if (cloud.has_colors()) {
    out.colors.reserve(indices.size());
    for (auto i : indices) out.colors.push_back(cloud.colors[i]);
  }
  if (cloud.has_face_ids()) {
    out.face_ids.reserve(indices.size());
    for (auto i : indices) out.face_ids.push_back(cloud.face_ids[i]);
  }
  return out;
}

}  // namespace springscan::analysis
