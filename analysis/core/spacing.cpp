#include "analysis/core/spacing.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>

namespace springscan::analysis {

double median_neighbour_spacing(const KdTree& tree, const std::vector<Vec3>& probes) {
  std::vector<double> nearest;
  nearest.reserve(probes.size());
  std::vector<Neighbor> two;
  for (const Vec3& p : probes) {
    tree.knn(p, 2, two);
    if (two.size() == 2) nearest.push_back(std::sqrt(two[1].squared_distance));
  }
  if (nearest.empty()) return 0.0;
  const auto mid = nearest.begin() + static_cast<std::ptrdiff_t>(nearest.size() / 2);
  std::nth_element(nearest.begin(), mid, nearest.end());
  return *mid;
}

}  // namespace springscan::analysis
