#pragma once
// The trend page of `springscan trend` (report/trend.hpp has the statistics): one
// self-contained HTML file, inline SVG and CSS, no script and nothing fetched. A table of the
// characteristics sorted by Cpk (worst first) links to one section per characteristic with its
// individuals chart (values, centre line, control limits, tolerance limits, the points that
// break a Western Electric rule in red) and its moving-range chart.

#include <string>
#include <vector>

#include "report/trend.hpp"

namespace springscan::report {

struct TrendPageInfo {
  std::string title = "springscan trend";
  std::vector<std::string> sources;  ///< the paths the reports were read from
  std::size_t reports = 0;
  std::size_t skipped = 0;  ///< files that were not readable reports
  std::string first_utc, last_utc;
  DecisionCounts decisions{};  ///< the part decisions of the reports read (decision_counts)
};

/// The page. Points are drawn as markers up to `max_markers` per chart (the line always);
/// flagged points always get a marker.
std::string render_trend_html(const std::vector<Characteristic>& characteristics,
                              const TrendPageInfo& info, std::size_t max_markers = 400);

}  // namespace springscan::report
