#pragma once
// Test and benchmark helper: even samples of a sheet profile's reference surface
// (simulators/parts/sheet_profile.hpp), with the path position of every sample, so tests know which
// samples lie on the free edges of the sheet and which on a bend.

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <vector>

#include "simulators/parts/sheet_profile.hpp"

// The analysis tests build their parts with simulators/parts.
namespace springscan::analysis {
using namespace springscan::parts;
}  // namespace springscan::analysis

namespace springscan::analysis::testing {

struct ProfileSamples {
  std::vector<Vec3> points;
  std::vector<int> path_step;  ///< index of the sample along the path (0 = start edge)
  int last_step = 0;           ///< path_step of the end edge
};

/// Samples every path element with `per_element[e]` intervals (so two profiles with the same
/// counts have the same number of points, sample for sample), and the width with `rows`
/// samples from y = 0 to y = width.
inline ProfileSamples sample_profile(const ProfileSpec& spec, const std::vector<int>& per_element,
                                     int rows) {
  ProfileSamples out;
  std::vector<Eigen::Vector2d> path_points;
  const auto path = profile_path(spec);
  for (std::size_t e = 0; e < path.size(); ++e) {
    const ProfileElement& el = path[e];
    const int n = per_element[std::min(e, per_element.size() - 1)];
    const int last = (e + 1 == path.size()) ? n : n - 1;  // the next element adds the joint
    for (int k = 0; k <= last; ++k) {
      const double t = static_cast<double>(k) / n;
      if (el.kind == ProfileElement::Kind::kLine) {
        path_points.push_back(el.start + t * (el.end - el.start));
      } else {
        const double a = el.start_angle_rad + t * el.sweep_rad;
        path_points.push_back(el.center + el.radius_mm * Eigen::Vector2d(std::cos(a), std::sin(a)));
      }
    }
  }
  out.last_step = static_cast<int>(path_points.size()) - 1;
  for (int r = 0; r < rows; ++r) {
    const double y = rows > 1 ? spec.width_mm * r / (rows - 1) : 0.0;
    for (std::size_t s = 0; s < path_points.size(); ++s) {
      out.points.push_back(profile_to_3d(path_points[s], y));
      out.path_step.push_back(static_cast<int>(s));
    }
  }
  return out;
}

/// Samples spaced about `spacing_mm` along the path and across the width.
inline ProfileSamples sample_profile_spacing(const ProfileSpec& spec, double spacing_mm) {
  std::vector<int> counts;
  for (const auto& el : profile_path(spec)) {
    counts.push_back(std::max(1, static_cast<int>(std::lround(el.length_mm() / spacing_mm))));
  }
  const int rows = std::max(2, static_cast<int>(std::lround(spec.width_mm / spacing_mm)) + 1);
  return sample_profile(spec, counts, rows);
}

}  // namespace springscan::analysis::testing
