#pragma once
// Vector (inline SVG) charts of the report: the global fit's error progression, as in the
// paper's Figure 6b, and the deviation colour bar.

#include <string>
#include <vector>

namespace springscan::report {

/// A "nice" tick step (1, 2 or 5 times a power of ten) giving about `target_ticks` ticks over
/// `range`. Returns 1 for a non-positive or non-finite range.
double nice_step(double range, int target_ticks);

struct ErrorPlotSettings {
  int panel_width_px = 340;  ///< each of the two panels
  int panel_height_px = 220;
  double ratio_stop = 0.0;  ///< the ICP stop threshold on E(i)/E(i-1), drawn when > 0
};

/// Two panels: E(i) over the iterations, and the quotient E(i)/E(i-1) with the line 1.0 (the
/// paper, section 3: a quotient near 1 means the fit stopped improving). E(0) is the error
/// before the first ICP step. An empty history gives a panel saying so. Returns an <svg>.
std::string error_progression_svg(const std::vector<double>& error_history,
                                  const ErrorPlotSettings& settings = {});

/// A horizontal colour bar from -scale_mm to +scale_mm in the report's deviation colours,
/// ticked in millimetres, with the tolerance band +-tolerance_mm marked (when > 0).
std::string color_bar_svg(double scale_mm, double tolerance_mm, int width_px = 560);

}  // namespace springscan::report
