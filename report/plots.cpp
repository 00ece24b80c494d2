#include "report/plots.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "report/colormap.hpp"
#include "report/html_text.hpp"

namespace springscan::report {
namespace {

// One chart panel: a plot area inside margins, data ranges mapped linearly to pixels.
struct Panel {
  double left, top, width, height;  // plot area in SVG pixels
  double x_min, x_max, y_min, y_max;
  double px(double x) const { return left + (x - x_min) / (x_max - x_min) * width; }
  double py(double y) const { return top + height - (y - y_min) / (y_max - y_min) * height; }
};

// Frame, grid lines and tick labels of a panel, then its title and axis labels.
void draw_axes(std::ostringstream& svg, const Panel& p, const std::string& title,
               const std::string& x_label, const std::string& y_label, int y_decimals) {
  svg << "<text x='" << svg_number(p.left) << "' y='" << svg_number(p.top - 8) << "' class='ttl'>"
      << escape_html(title) << "</text>";
  const double y_step = nice_step(p.y_max - p.y_min, 5);
  for (double y = std::ceil(p.y_min / y_step) * y_step; y <= p.y_max + 1e-9 * y_step; y += y_step) {
    svg << "<line x1='" << svg_number(p.left) << "' x2='" << svg_number(p.left + p.width)
        << "' y1='" << svg_number(p.py(y)) << "' y2='" << svg_number(p.py(y))
        << "' class='grid'/><text x='" << svg_number(p.left - 4) << "' y='"
        << svg_number(p.py(y) + 3.5) << "' text-anchor='end'>" << fixed(y, y_decimals) << "</text>";
  }
  const double x_step = std::max(1.0, nice_step(p.x_max - p.x_min, 6));
  for (double x = std::ceil(p.x_min / x_step) * x_step; x <= p.x_max + 1e-9; x += x_step) {
    svg << "<text x='" << svg_number(p.px(x)) << "' y='" << svg_number(p.top + p.height + 13)
        << "' text-anchor='middle'>" << fixed(x, 0) << "</text>";
  }
  svg << "<rect x='" << svg_number(p.left) << "' y='" << svg_number(p.top) << "' width='"
      << svg_number(p.width) << "' height='" << svg_number(p.height) << "' class='frame'/>";
  svg << "<text x='" << svg_number(p.left + p.width / 2) << "' y='"
      << svg_number(p.top + p.height + 28) << "' text-anchor='middle'>" << escape_html(x_label)
      << "</text>";
  svg << "<text transform='translate(" << svg_number(p.left - 40) << ' '
      << svg_number(p.top + p.height / 2) << ") rotate(-90)' text-anchor='middle'>"
      << escape_html(y_label) << "</text>";
}

// A polyline with a dot at every sample; x runs over first_x, first_x + 1, ...
void draw_series(std::ostringstream& svg, const Panel& p, const std::vector<double>& ys,
                 int first_x, const char* css_class) {
  svg << "<polyline class='" << css_class << "' points='";
  for (std::size_t i = 0; i < ys.size(); ++i)
    svg << svg_number(p.px(first_x + static_cast<double>(i))) << ',' << svg_number(p.py(ys[i]))
        << ' ';
  svg << "'/>";
  if (ys.size() > 200) return;  // a long history stays a line: dots would only clutter it
  for (std::size_t i = 0; i < ys.size(); ++i)
    svg << "<circle class='" << css_class << "' cx='"
        << svg_number(p.px(first_x + static_cast<double>(i))) << "' cy='" << svg_number(p.py(ys[i]))
        << "' r='2.5'/>";
}

void draw_hline(std::ostringstream& svg, const Panel& p, double y, const std::string& label) {
  if (y < p.y_min || y > p.y_max) return;
  svg << "<line x1='" << svg_number(p.left) << "' x2='" << svg_number(p.left + p.width) << "' y1='"
      << svg_number(p.py(y)) << "' y2='" << svg_number(p.py(y)) << "' class='ref'/><text x='"
      << svg_number(p.left + p.width - 4) << "' y='" << svg_number(p.py(y) - 4)
      << "' text-anchor='end' class='reflabel'>" << escape_html(label) << "</text>";
}

}  // namespace

double nice_step(double range, int target_ticks) {
  if (!(range > 0.0) || !std::isfinite(range) || target_ticks < 1) return 1.0;
  const double raw = range / target_ticks;
  const double power = std::pow(10.0, std::floor(std::log10(raw)));
  const double fraction = raw / power;
  const double nice = fraction < 1.5 ? 1.0 : fraction < 3.5 ? 2.0 : fraction < 7.5 ? 5.0 : 10.0;
  return nice * power;
}

std::string error_progression_svg(const std::vector<double>& history,
                                  const ErrorPlotSettings& settings) {
  const double pw = settings.panel_width_px, ph = settings.panel_height_px;
  std::ostringstream svg;
  svg << "<svg class='chart' viewBox='0 0 " << svg_number(2 * pw) << ' ' << svg_number(ph)
      << "' width='" << svg_number(2 * pw) << "' height='" << svg_number(ph)
      << "' role='img' aria-label='ICP error progression'>";
  std::vector<double> errors;
  for (double e : history)
    if (std::isfinite(e)) errors.push_back(e);
  if (errors.empty()) {
    svg << "<text x='" << svg_number(pw) << "' y='" << svg_number(ph / 2)
        << "' text-anchor='middle'>No error history in this report.</text></svg>";
    return svg.str();
  }
  const double last = static_cast<double>(std::max<std::size_t>(errors.size() - 1, 1));
  const double e_max = *std::max_element(errors.begin(), errors.end());
  Panel left{58, 24, pw - 76, ph - 62, 0, last, 0, e_max > 0 ? e_max * 1.05 : 1.0};
  draw_axes(svg, left, "Error E(i)", "iteration i", "E(i)  [mm\u00b2]",
            e_max >= 100 ? 0
            : e_max >= 1 ? 1
                         : 3);
  draw_series(svg, left, errors, 0, "s1");

  std::vector<double> ratios;
  for (std::size_t i = 1; i < errors.size(); ++i)
    ratios.push_back(errors[i - 1] > 0 ? errors[i] / errors[i - 1] : 1.0);
  double r_max = 1.1;
  for (double r : ratios) r_max = std::max(r_max, std::min(r, 10.0) * 1.05);
  Panel right{pw + 58, 24, pw - 76, ph - 62, 1, std::max(last, 2.0), 0, r_max};
  draw_axes(svg, right, "Quotient E(i) / E(i-1)", "iteration i", "E(i) / E(i-1)", 2);
  draw_hline(svg, right, 1.0, "1.0");
  if (settings.ratio_stop > 0)
    draw_hline(svg, right, settings.ratio_stop, "stop " + fixed(settings.ratio_stop, 3));
  for (double& r : ratios) r = std::min(r, r_max);
  if (!ratios.empty()) draw_series(svg, right, ratios, 1, "s2");
  svg << "</svg>";
  return svg.str();
}

std::string color_bar_svg(double scale_mm, double tolerance_mm, int width_px) {
  const double w = std::max(width_px, 200), bar_left = 24, bar_w = w - 48, bar_top = 24, bar_h = 18;
  std::ostringstream svg;
  svg << "<svg class='colorbar' viewBox='0 0 " << svg_number(w) << " 64' width='" << svg_number(w)
      << "' height='64' role='img' aria-label='deviation colour scale in mm'>"
      << "<defs><linearGradient id='devscale' x1='0' x2='1' y1='0' y2='0'>";
  for (int i = 0; i <= 8; ++i) {
    const double t = i / 8.0;
    svg << "<stop offset='" << svg_number(t) << "' stop-color='"
        << css_color(deviation_color((2 * t - 1) * scale_mm, scale_mm)) << "'/>";
  }
  svg << "</linearGradient></defs>";
  const auto x_of = [&](double d) { return bar_left + (d + scale_mm) / (2 * scale_mm) * bar_w; };
  svg << "<rect x='" << svg_number(bar_left) << "' y='" << svg_number(bar_top) << "' width='"
      << svg_number(bar_w) << "' height='" << svg_number(bar_h)
      << "' fill='url(#devscale)' stroke='#7d8796'/>";
  const double step = nice_step(2 * scale_mm, 8);
  const int decimals = step >= 1 ? 0 : step >= 0.1 ? 1 : step >= 0.01 ? 2 : 3;
  for (double d = std::ceil(-scale_mm / step) * step; d <= scale_mm + 1e-9 * step; d += step) {
    svg << "<line x1='" << svg_number(x_of(d)) << "' x2='" << svg_number(x_of(d)) << "' y1='"
        << svg_number(bar_top + bar_h) << "' y2='" << svg_number(bar_top + bar_h + 4)
        << "' class='tick'/><text x='" << svg_number(x_of(d)) << "' y='"
        << svg_number(bar_top + bar_h + 16) << "' text-anchor='middle'>"
        << signed_fixed(d, decimals) << "</text>";
  }
  svg << "<text x='" << svg_number(w - bar_left) << "' y='14' text-anchor='end'>deviation "
      << "[mm]: blue below the CAD surface, green on it, red above</text>";
  if (tolerance_mm > 0 && tolerance_mm <= scale_mm) {
    for (double d : {-tolerance_mm, tolerance_mm}) {
      svg << "<line x1='" << svg_number(x_of(d)) << "' x2='" << svg_number(x_of(d)) << "' y1='"
          << svg_number(bar_top - 4) << "' y2='" << svg_number(bar_top + bar_h)
          << "' class='tol'/>";
    }
    svg << "<text x='" << svg_number(bar_left) << "' y='14' class='tollabel'>\u25bc tolerance "
        << "\u00b1" << fixed(tolerance_mm, 3) << " mm (black marks)</text>";
  }
  svg << "</svg>";
  return svg.str();
}

}  // namespace springscan::report
