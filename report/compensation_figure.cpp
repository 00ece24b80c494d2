// The compensation picture: the vectors c = -alpha * d at the model control points (DESIGN.md
// stage 9) as arrows on the deviation map, in the standard view that shows them longest. Read by
// a tool designer against the colours: arrows haloed so they stand out on red and blue, drawn at
// a round scale (1, 2 or 5 x 10^k) with a key arrow of a round length in the corner.
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

// The largest of 1, 2, 5 x 10^k that is not above x (x > 0): a scale a person reads at once.
double round_down_125(double x) {
  const double decade = std::pow(10.0, std::floor(std::log10(x)));
  for (double m : {5.0, 2.0}) {
    if (m * decade <= x) return m * decade;
  }
  return decade;
}

struct ArrowScale {
  double gain = 1.0;    ///< drawn length / true length (projected)
  double key_mm = 0.0;  ///< the key arrow's length; 0: no key (no vector has a length)
};

// The longest projected arrow about 12 % of the picture's smaller side, the gain rounded down to
// 1, 2 or 5 x 10^k; the key arrow a round length near half the longest vector.
ArrowScale arrow_scale(const v1::InspectionReport& report, const ViewProjection& view) {
  double longest_px = 0.0, longest_mm = 0.0;
  for (const auto& c : report.compensation()) {
    longest_px = std::max(longest_px, view.direction_to_pixel(to_vec(c.vector())).norm());
    longest_mm = std::max(longest_mm, to_vec(c.vector()).norm());
  }
  ArrowScale scale;
  if (!(longest_px > 0.0) || !(longest_mm > 0.0)) return scale;
  scale.gain = round_down_125(0.12 * std::min(view.width_px, view.height_px) / longest_px);
  scale.key_mm = round_down_125(0.5 * longest_mm);
  return scale;
}

// One arrow: a white halo under a dark line, so it reads on every colour of the map.
void draw_arrow(std::ostringstream& svg, const Eigen::Vector2d& from, const Eigen::Vector2d& to) {
  const auto line = [&](const char* cls, const char* marker) {
    svg << "<line class='" << cls << "' x1='" << svg_number(from.x()) << "' y1='"
        << svg_number(from.y()) << "' x2='" << svg_number(to.x()) << "' y2='" << svg_number(to.y())
        << "' marker-end='url(#" << marker << ")'/>";
  };
  line("halo", "arrowhalo");
  line("arrow", "arrowhead");
}

// The key in the picture's lower right corner (the axis triad has the left): an arrow of key_mm
// at the figure's gain, labelled.
void draw_key(std::ostringstream& svg, const ViewProjection& view, const ViewBasis& basis,
              const ArrowScale& scale) {
  if (scale.key_mm <= 0.0) return;
  const double length_px = scale.gain * view.direction_to_pixel(basis.right * scale.key_mm).norm();
  const double box_w = length_px + 84.0, box_x = view.width_px - 6.0 - box_w;
  const Eigen::Vector2d from(box_x + 10.0, view.height_px - 23.0);
  const Eigen::Vector2d to = from + Eigen::Vector2d(length_px, 0.0);
  svg << "<g class='key'><rect x='" << svg_number(box_x) << "' y='"
      << svg_number(view.height_px - 40.0) << "' width='" << svg_number(box_w)
      << "' height='34' rx='3'/>";
  draw_arrow(svg, from, to);
  svg << "<text x='" << svg_number(to.x() + 8.0) << "' y='" << svg_number(from.y() + 4.0) << "'>"
      << fixed(scale.key_mm, scale.key_mm < 0.1 ? 2
                             : scale.key_mm < 1 ? 1
                                                : 0)
      << " mm</text></g>";
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

  const ArrowScale scale = arrow_scale(report, view);
  std::ostringstream overlay;
  overlay << "<defs>"
             "<marker id='arrowhead' viewBox='0 0 10 10' refX='9' refY='5' markerWidth='5' "
             "markerHeight='5' orient='auto-start-reverse'><path d='M0,0 L10,5 L0,10 z' "
             "fill='#111'/></marker>"
             "<marker id='arrowhalo' viewBox='-2 -2 14 14' refX='9' refY='5' markerWidth='4.2' "
             "markerHeight='4.2' orient='auto-start-reverse'><path d='M0,0 L10,5 L0,10 z' "
             "fill='#fff' stroke='#fff' stroke-width='3'/></marker></defs>";
  const auto chosen = subsample_indices(static_cast<std::size_t>(report.compensation_size()),
                                        settings.max_arrows, settings.seed);
  for (auto i : chosen) {
    const auto& c = report.compensation(static_cast<int>(i));
    const Eigen::Vector2d from = view.to_pixel(to_vec(c.point()));
    const Eigen::Vector2d to = from + scale.gain * view.direction_to_pixel(to_vec(c.vector()));
    if (!from.allFinite() || !to.allFinite()) continue;
    overlay << "<circle class='anchor' cx='" << svg_number(from.x()) << "' cy='"
            << svg_number(from.y()) << "' r='1.8'/>";
    if ((to - from).norm() >= 1.0) draw_arrow(overlay, from, to);
  }
  draw_key(overlay, view, view_basis(kind), scale);
  // On the deviation map (when there is a cloud): the arrows say where to move the die, the
  // colours where the part is out.
  const bool on_map = !cloud.points.empty();
  auto svg = view_svg(cloud.points, on_map ? cloud.deviation_colors : cloud.grey_colors,
                      cloud.spacing_mm, view, settings, overlay.str(),
                      "compensation vectors as arrows on the deviation map");
  if (!svg) return svg.error();
  std::string caption =
      std::string("Compensation vectors c = \u2212\u03b1\u00b7d, ") + view_name(kind) + " view" +
      (on_map ? ", on the deviation map (colours as in the deviation views)" : "") +
      "; arrows drawn " + fixed(scale.gain, scale.gain < 1 ? 2 : 0) + " \u00d7 their length";
  if (scale.key_mm > 0.0) caption += " (key arrow: " + fixed(scale.key_mm, 2) + " mm)";
  if (chosen.size() < static_cast<std::size_t>(report.compensation_size()))
    caption += " (" + std::to_string(chosen.size()) + " of " +
               std::to_string(report.compensation_size()) + " shown)";
  return "<figure class='view'>" + *svg + "<figcaption>" + escape_html(caption) +
         "</figcaption></figure>";
}

}  // namespace springscan::report
