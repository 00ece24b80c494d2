// The compensation picture: the vectors c = -alpha * d at the model control points (DESIGN.md
// stage 9) as arrows on the standard view that shows them longest.
#include <algorithm>
#include <cmath>
#include <sstream>

#include "report/figures.hpp"
#include "report/html_text.hpp"
#include "report/raster.hpp"

namespace springscan::report {
namespace {

Vec3 to_vec(const v1::Vec3& v) { return {v.x(), v.y(), v.z()}; }

// The view in which the vectors' summed projected length is largest: for a bent profile that
// is the section view, where springback moves the flanges.
ViewKind best_view(const v1::InspectionReport& report) {
  ViewKind best = ViewKind::kIsometric;
  double best_sum = -1.0;
  for (auto kind : {ViewKind::kFront, ViewKind::kSide, ViewKind::kTop, ViewKind::kIsometric}) {
    const ViewBasis b = view_basis(kind);
    double sum = 0.0;
    for (const auto& c : report.compensation()) {
      const Vec3 v = to_vec(c.vector());
      sum += std::hypot(v.dot(b.right), v.dot(b.up));
    }
    if (sum > best_sum * 1.02) best = kind, best_sum = sum;  // prefer earlier views on a tie
  }
  return best;
}

}  // namespace

analysis::Expected<std::string> compensation_figure_html(const v1::InspectionReport& report,
                                                         const DrawCloud& cloud,
                                                         const ReportSettings& settings) {
  if (report.compensation_size() == 0)
    return std::string("<p class='note'>No compensation vectors in this report.</p>");
  const ViewKind kind = best_view(report);
  std::vector<Vec3> anchors;
  for (const auto& c : report.compensation()) anchors.push_back(to_vec(c.point()));
  const std::vector<Vec3>& frame_points = cloud.points.empty() ? anchors : cloud.points;
  const ViewProjection view =
      fit_view(frame_points, kind, {settings.view_width_px, settings.view_height_px, 40});

  // The longest arrow is drawn 12 % of the picture's smaller side long.
  double longest_px = 0.0;
  for (const auto& c : report.compensation())
    longest_px = std::max(longest_px, view.direction_to_pixel(to_vec(c.vector())).norm());
  const double gain =
      longest_px > 0 ? 0.12 * std::min(view.width_px, view.height_px) / longest_px : 1.0;

  std::ostringstream overlay;
  overlay << "<defs><marker id='arrowhead' viewBox='0 0 10 10' refX='9' refY='5' "
             "markerWidth='5' markerHeight='5' orient='auto-start-reverse'><path d='M0,0 "
             "L10,5 L0,10 z' fill='#1d2b53'/></marker></defs>";
  const auto chosen = subsample_indices(static_cast<std::size_t>(report.compensation_size()),
                                        settings.max_arrows, settings.seed);
  for (auto i : chosen) {
    const auto& c = report.compensation(static_cast<int>(i));
    const Eigen::Vector2d from = view.to_pixel(to_vec(c.point()));
    const Eigen::Vector2d to = from + gain * view.direction_to_pixel(to_vec(c.vector()));
    if (!from.allFinite() || !to.allFinite()) continue;
    overlay << "<circle class='anchor' cx='" << svg_number(from.x()) << "' cy='"
            << svg_number(from.y()) << "' r='1.8'/>";
    if ((to - from).norm() < 1.0) continue;
    overlay << "<line class='arrow' x1='" << svg_number(from.x()) << "' y1='"
            << svg_number(from.y()) << "' x2='" << svg_number(to.x()) << "' y2='"
            << svg_number(to.y()) << "' marker-end='url(#arrowhead)'/>";
  }
  auto svg = view_svg(cloud.points, cloud.grey_colors, cloud.spacing_mm, view, settings,
                      overlay.str(), "compensation vectors as arrows");
  if (!svg) return svg.error();
  std::string caption = std::string("Compensation vectors, ") + view_name(kind) +
                        " view; arrows drawn " + fixed(gain, gain < 10 ? 1 : 0) +
                        " \u00d7 their length";
  if (chosen.size() < static_cast<std::size_t>(report.compensation_size()))
    caption += " (" + std::to_string(chosen.size()) + " of " +
               std::to_string(report.compensation_size()) + " shown)";
  return "<figure class='view'>" + *svg + "<figcaption>" + escape_html(caption) +
         "</figcaption></figure>";
}

}  // namespace springscan::report
