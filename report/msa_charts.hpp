#pragma once
// The inline SVG charts of the gauge study pages (report/msa_html.hpp): a type-1 run chart and
// histogram, and a type-3 chart of the trials part by part. Self-contained <svg> elements,
// nothing fetched.

#include <string>
#include <vector>

namespace springscan::report {

/// A horizontal line drawn across a chart, with its label.
struct ChartLine {
  double value = 0.0;
  std::string label;            ///< HTML-safe text
  std::string colour = "#444";  ///< CSS colour
  bool dashed = false;
};

/// The values in measurement order (x: 1..n), joined, with `lines` across.
std::string run_chart_svg(const std::vector<double>& values, const std::vector<ChartLine>& lines,
                          const std::string& unit);

/// A histogram of `values` (sqrt(n) bins, at least 5), with `lines` as vertical marks.
std::string histogram_svg(const std::vector<double>& values, const std::vector<ChartLine>& lines,
                          const std::string& unit);

/// `values` holds `parts` blocks of `trials` values: each part's trials as dots above its
/// number, its mean as a bar, the means joined.
std::string parts_chart_svg(const std::vector<double>& values, std::size_t parts,
                            std::size_t trials, const std::string& unit);

}  // namespace springscan::report
