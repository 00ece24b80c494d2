#pragma once
// The pipeline's k-center reduction (paper section 2) to exactly n centers, as points: the
// matching benchmarks' instances (bench_matching, bench_cli_match).

#include <cstddef>
#include <vector>

#include "analysis/preprocess/kcenter.hpp"

namespace springscan::analysis::bench {

inline std::vector<Vec3> kcenter_centers(const std::vector<Vec3>& points, std::size_t n) {
  KCenterSettings settings;
  settings.center_count = n;
  const auto reduced = kcenter_reduce(points, settings);
  std::vector<Vec3> centers;
  if (!reduced) return centers;
  for (const auto i : reduced->centers) centers.push_back(points[i]);
  return centers;
}

}  // namespace springscan::analysis::bench
