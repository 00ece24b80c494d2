#pragma once
// The deviation colour scale of the report: blue below the CAD surface, green on it, red above
// (the convention of the paper's Figure 7 and of metrology software), with cyan and yellow
// between so that the tolerance band reads at a glance.

#include <string>

#include "analysis/core/point_cloud.hpp"

namespace springscan::report {

using analysis::Rgb;

/// The colour of a signed deviation on a scale of +-scale_mm: -scale_mm and below blue,
/// 0 green, +scale_mm and above red. NaN (or scale_mm <= 0) gives neutral grey.
Rgb deviation_color(double deviation_mm, double scale_mm);

/// "#rrggbb" for CSS and SVG.
std::string css_color(Rgb color);

}  // namespace springscan::report
