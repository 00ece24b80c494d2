#include "report/msa_charts.hpp"

#include <algorithm>
#include <cmath>

#include "report/html_text.hpp"

namespace springscan::report {

namespace {

constexpr double kWidth = 640.0, kHeight = 240.0;
constexpr double kLeft = 70.0, kRight = 16.0, kTop = 14.0, kBottom = 28.0;

/// Maps data to pixels: x over [x0, x1], y over [y0, y1] (padded).
struct Frame {
  double x0, x1, y0, y1;
  double px(double x) const {
    return kLeft + (kWidth - kLeft - kRight) * (x1 > x0 ? (x - x0) / (x1 - x0) : 0.5);
  }
  double py(double y) const { return kTop + (kHeight - kTop - kBottom) * (y1 - y) / (y1 - y0); }
};

std::string num(double v) { return svg_number(v); }

std::string value_text(double v) {
  const double a = std::abs(v);
  return fixed(v, a >= 100 ? 1 : a >= 1 ? 3 : 4);
}

/// The y range of `values` and `lines`, padded, never empty.
std::pair<double, double> y_range(const std::vector<double>& values,
                                  const std::vector<ChartLine>& lines) {
  std::vector<double> all = values;
  for (const auto& l : lines) all.push_back(l.value);
  double lo = all.empty() ? 0.0 : *std::min_element(all.begin(), all.end());
  double hi = all.empty() ? 1.0 : *std::max_element(all.begin(), all.end());
  if (!(hi > lo)) {
    lo -= 1e-3 + std::abs(lo) * 0.05;
    hi += 1e-3 + std::abs(hi) * 0.05;
  }
  const double pad = 0.08 * (hi - lo);
  return {lo - pad, hi + pad};
}

std::string open_svg(const char* css_class, const std::string& label) {
  return std::string("<svg class=\"") + css_class +
         "\" xmlns=\"http://www.w3.org/2000/svg\" width=\"" + num(kWidth) + "\" height=\"" +
         num(kHeight) + "\" viewBox=\"0 0 " + num(kWidth) + " " + num(kHeight) +
         "\" role=\"img\" aria-label=\"" + escape_html(label) + "\">";
}

/// The frame's box, 5 value ticks on the y axis (or the x axis when `vertical_values`), and the
/// axis captions.
std::string axes(const Frame& f, const std::string& value_unit, const std::string& other_caption,
                 bool vertical_values) {
  std::string svg = "<rect x=\"" + num(kLeft) + "\" y=\"" + num(kTop) + "\" width=\"" +
                    num(kWidth - kLeft - kRight) + "\" height=\"" + num(kHeight - kTop - kBottom) +
                    "\" fill=\"none\" stroke=\"#c5ccd4\"/>";
  for (int k = 0; k <= 4; ++k) {
    if (vertical_values) {
      const double v = f.x0 + (f.x1 - f.x0) * k / 4.0;
      svg += "<text x=\"" + num(f.px(v)) + "\" y=\"" + num(kHeight - 12) +
             "\" font-size=\"11\" text-anchor=\"middle\" fill=\"#5a6470\">" + value_text(v) +
             "</text>";
    } else {
      const double v = f.y0 + (f.y1 - f.y0) * k / 4.0;
      svg += "<text x=\"" + num(kLeft - 6) + "\" y=\"" + num(f.py(v) + 4) +
             "\" font-size=\"11\" text-anchor=\"end\" fill=\"#5a6470\">" + value_text(v) +
             "</text>";
    }
  }
  svg += "<text x=\"" + num(kWidth - kRight) + "\" y=\"" + num(kHeight - 1) +
         "\" font-size=\"11\" text-anchor=\"end\" fill=\"#5a6470\">" +
         escape_html(vertical_values ? value_unit : other_caption) + "</text>";
  svg += "<text x=\"12\" y=\"" + num(kHeight / 2) +
         "\" font-size=\"11\" fill=\"#5a6470\" text-anchor=\"middle\" transform=\"rotate(-90 12 " +
         num(kHeight / 2) + ")\">" + escape_html(vertical_values ? other_caption : value_unit) +
         "</text>";
  return svg;
}

std::string line_svg(double x1, double y1, double x2, double y2, const ChartLine& l) {
  return "<line x1=\"" + num(x1) + "\" y1=\"" + num(y1) + "\" x2=\"" + num(x2) + "\" y2=\"" +
         num(y2) + "\" stroke=\"" + l.colour + "\" stroke-width=\"1.2\"" +
         (l.dashed ? " stroke-dasharray=\"6 4\"" : "") + "/>";
}

std::string label_svg(double x, double y, const ChartLine& l, const char* anchor) {
  return "<text x=\"" + num(x) + "\" y=\"" + num(y) + "\" font-size=\"11\" text-anchor=\"" +
         anchor + "\" fill=\"" + l.colour + "\">" + l.label + "</text>";
}

}  // namespace

std::string run_chart_svg(const std::vector<double>& values, const std::vector<ChartLine>& lines,
                          const std::string& unit) {
  const auto [lo, hi] = y_range(values, lines);
  const Frame f{1.0, static_cast<double>(std::max<std::size_t>(values.size(), 1)), lo, hi};
  std::string svg = open_svg("run-chart", "run chart") +
                    axes(f, unit, "measurement 1.." + std::to_string(values.size()), false);
  for (std::size_t i = 0; i < lines.size(); ++i) {
    const ChartLine& l = lines[i];
    svg += line_svg(kLeft, f.py(l.value), kWidth - kRight, f.py(l.value), l);
    // Labels alternate between the ends, so that close lines (reference, mean) stay readable.
    if (i % 2 == 0) {
      svg += label_svg(kWidth - kRight - 4, f.py(l.value) - 3, l, "end");
    } else {
      svg += label_svg(kLeft + 4, f.py(l.value) - 3, l, "start");
    }
  }
  svg += "<polyline fill=\"none\" stroke=\"#7d8a97\" stroke-width=\"1\" points=\"";
  for (std::size_t i = 0; i < values.size(); ++i) {
    // Appended piece by piece: `"" + std::string` trips a g++ 12 -Wrestrict false positive.
    if (i != 0) svg.push_back(' ');
    svg += num(f.px(static_cast<double>(i + 1)));
    svg.push_back(',');
    svg += num(f.py(values[i]));
  }
  svg += "\"/>";
  for (std::size_t i = 0; i < values.size(); ++i)
    svg += "<circle class=\"value\" cx=\"" + num(f.px(static_cast<double>(i + 1))) + "\" cy=\"" +
           num(f.py(values[i])) + "\" r=\"2.4\" fill=\"#2b3a4a\"/>";
  return svg + "</svg>";
}

std::string histogram_svg(const std::vector<double>& values, const std::vector<ChartLine>& lines,
                          const std::string& unit) {
  const auto [lo, hi] = y_range(values, lines);
  const std::size_t bins = std::max<std::size_t>(
      5, static_cast<std::size_t>(std::ceil(std::sqrt(static_cast<double>(values.size())))));
  const double vlo = values.empty() ? lo : *std::min_element(values.begin(), values.end());
  const double vhi = values.empty() ? hi : *std::max_element(values.begin(), values.end());
  const double width = vhi > vlo ? (vhi - vlo) / static_cast<double>(bins) : (hi - lo) / 10.0;
  std::vector<std::size_t> count(bins, 0);
  for (const double v : values)
    ++count[std::min(bins - 1, static_cast<std::size_t>((v - vlo) / width))];
  const std::size_t most = count.empty() ? 1 : *std::max_element(count.begin(), count.end());
  const Frame f{lo, hi, 0.0, static_cast<double>(std::max<std::size_t>(most, 1)) * 1.1};
  std::string svg = open_svg("histogram", "histogram") + axes(f, unit, "count", true);
  for (std::size_t b = 0; b < bins; ++b) {
    const double x = vlo + width * static_cast<double>(b);
    svg += "<rect class=\"bin\" x=\"" + num(f.px(x)) + "\" y=\"" +
           num(f.py(static_cast<double>(count[b]))) + "\" width=\"" +
           num(std::max(1.0, f.px(x + width) - f.px(x) - 1.0)) + "\" height=\"" +
           num(f.py(0.0) - f.py(static_cast<double>(count[b]))) + "\" fill=\"#8fa9c4\"><title>" +
           std::to_string(count[b]) + "</title></rect>";
  }
  for (std::size_t i = 0; i < lines.size(); ++i) {
    const ChartLine& l = lines[i];
    const double x = f.px(l.value);
    svg += line_svg(x, kTop, x, kHeight - kBottom, l);
    // One text row per line; right of the line in the left half, left of it in the right half.
    const bool right_half = x > 0.5 * (kLeft + kWidth - kRight);
    svg += label_svg(right_half ? x - 3 : x + 3, kTop + 11 + 13 * static_cast<double>(i), l,
                     right_half ? "end" : "start");
  }
  return svg + "</svg>";
}

std::string parts_chart_svg(const std::vector<double>& values, std::size_t parts,
                            std::size_t trials, const std::string& unit) {
  const auto [lo, hi] = y_range(values, {});
  const Frame f{0.5, static_cast<double>(parts) + 0.5, lo, hi};
  std::string svg = open_svg("parts-chart", "trials by part") +
                    axes(f, unit, "part 1.." + std::to_string(parts), false);
  std::string means = "<polyline fill=\"none\" stroke=\"#2f6fb5\" stroke-width=\"1\" points=\"";
  for (std::size_t p = 0; p < parts && (p + 1) * trials <= values.size(); ++p) {
    const double x = f.px(static_cast<double>(p + 1));
    double sum = 0.0;
    for (std::size_t t = 0; t < trials; ++t) {
      const double v = values[p * trials + t];
      sum += v;
      svg += "<circle class=\"value\" cx=\"" + num(x) + "\" cy=\"" + num(f.py(v)) +
             "\" r=\"2.6\" fill=\"#2b3a4a\" fill-opacity=\"0.7\"/>";
    }
    const double y = f.py(sum / static_cast<double>(trials));
    svg += "<line x1=\"" + num(x - 8) + "\" x2=\"" + num(x + 8) + "\" y1=\"" + num(y) + "\" y2=\"" +
           num(y) + "\" stroke=\"#2f6fb5\" stroke-width=\"2\"/>";
    if (p != 0) means.push_back(' ');
    means += num(x);
    means.push_back(',');
    means += num(y);
  }
  return svg + means + "\"/></svg>";
}

}  // namespace springscan::report
