#pragma once
// The spacing of a sampling: how far apart its points lie, as the median distance from each
// point to its nearest neighbour. The deformation field's smoothing radius, the compensation's
// support and the orientation's sample spacing all take it.

#include <vector>

#include "analysis/core/kdtree.hpp"

namespace springscan::analysis {

/// The median distance from each of `probes` (points of the tree) to its nearest other tree
/// point (the reduced model's is about the k-center radius w). 0 when no probe has a neighbour.
double median_neighbour_spacing(const KdTree& tree, const std::vector<Vec3>& probes);

}  // namespace springscan::analysis
