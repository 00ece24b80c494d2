#include "report/figures.hpp"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <sstream>
#include <thread>

#include "report/colormap.hpp"
#include "report/html_text.hpp"
#include "report/png.hpp"
#include "report/raster.hpp"

namespace springscan::report {
namespace {

constexpr Rgb kGrey = {178, 184, 192};

Vec3 to_vec(const v1::Vec3& v) { return {v.x(), v.y(), v.z()}; }

ViewSettings view_settings(const ReportSettings& settings) {
  return {settings.view_width_px, settings.view_height_px, 18};
}

// A small x/y/z triad in the lower left corner, so the reader knows how the view is turned.
std::string axis_triad(const ViewProjection& view) {
  std::ostringstream svg;
  const Eigen::Vector2d origin(26, view.height_px - 26);
  const char* names[3] = {"x", "y", "z"};
  const char* colors[3] = {"#c0392b", "#27ae60", "#2c5fb8"};
  for (int a = 0; a < 3; ++a) {
    Eigen::Vector2d d = view.direction_to_pixel(Vec3::Unit(a)) / view.scale_px_per_mm;
    const Eigen::Vector2d tip = origin + 18.0 * d;
    const Eigen::Vector2d label = origin + (d.norm() < 0.2 ? Eigen::Vector2d(6, -6) : 25.0 * d);
    svg << "<line x1='" << svg_number(origin.x()) << "' y1='" << svg_number(origin.y()) << "' x2='"
        << svg_number(tip.x()) << "' y2='" << svg_number(tip.y()) << "' stroke='" << colors[a]
        << "' stroke-width='2'/><text x='" << svg_number(label.x() - 3) << "' y='"
        << svg_number(label.y() + 4) << "' fill='" << colors[a] << "' class='triad'>" << names[a]
        << "</text>";
  }
  return svg.str();
}

std::string missing_picture(const ReportSettings& settings) {
  return "<p class='missing'>Picture missing: " +
         escape_html(settings.missing_cloud_note.empty() ? "no deviation cloud was given"
                                                         : settings.missing_cloud_note) +
         ".</p>";
}

}  // namespace

double surface_spacing_mm(const std::vector<Vec3>& points) {
  if (points.size() < 2) return 0.0;
  Eigen::AlignedBox3d box;
  for (const auto& p : points)
    if (p.allFinite()) box.extend(p);
  const double voxel = box.diagonal().norm() / 150.0;
  if (!(voxel > 0)) return 0.0;
  std::vector<std::uint64_t> keys;
  keys.reserve(points.size());
  for (const auto& p : points) {
    if (!p.allFinite()) continue;
    const Eigen::Vector3d c = (p - box.min()) / voxel;  // 0 .. ~150 per axis
    keys.push_back((static_cast<std::uint64_t>(c.x()) << 42) |
                   (static_cast<std::uint64_t>(c.y()) << 21) | static_cast<std::uint64_t>(c.z()));
  }
  if (keys.empty()) return 0.0;
  std::sort(keys.begin(), keys.end());
  const auto occupied = static_cast<double>(std::unique(keys.begin(), keys.end()) - keys.begin());
  return std::sqrt(occupied * voxel * voxel / static_cast<double>(keys.size()));
}

analysis::Expected<std::string> view_svg(const std::vector<Vec3>& points,
                                         const std::vector<Rgb>& colors, double spacing_mm,
                                         const ViewProjection& view, const ReportSettings& settings,
                                         const std::string& overlay, const std::string& label) {
  int radius = settings.splat_radius_px;
  if (radius <= 0) {
    // Half the point spacing in pixels, rounded up, covers the gaps of a random sample.
    const double spacing_px = spacing_mm * view.scale_px_per_mm;
    // Clamped as a double first: a degenerate view can make spacing_px huge or NaN.
    const double wanted = std::isfinite(spacing_px) ? std::ceil(0.75 * spacing_px) : 1.0;
    radius = static_cast<int>(std::clamp(wanted, 1.0, 6.0));
  }
  const RgbImage image =
      render_points(points, colors, view, {radius, {255, 255, 255}, settings.shading});
  auto png = encode_png(image, {settings.png_compression_level});
  if (!png) return png.error();
  std::ostringstream svg;
  svg << "<svg class='view' viewBox='0 0 " << view.width_px << ' ' << view.height_px << "' width='"
      << view.width_px << "' height='" << view.height_px << "' role='img' aria-label='"
      << escape_html(label) << "'><image width='" << view.width_px << "' height='" << view.height_px
      << "' href='data:image/png;base64," << base64(*png) << "'/>" << axis_triad(view) << overlay
      << "</svg>";
  return svg.str();
}

DrawCloud make_draw_cloud(const analysis::PointCloud& cloud, double scale_mm,
                          const ReportSettings& settings) {
  DrawCloud out;
  const auto indices = subsample_indices(cloud.size(), settings.max_points, settings.seed);
  const bool scalars = cloud.scalars.size() == cloud.size();
  const bool colors = cloud.colors.size() == cloud.size();
  out.points.reserve(indices.size());
  out.deviation_colors.reserve(indices.size());
  for (auto i : indices) {
    out.points.push_back(cloud.points[i]);
    out.deviation_colors.push_back(scalars  ? deviation_color(cloud.scalars[i], scale_mm)
                                   : colors ? cloud.colors[i]
                                            : kGrey);
  }
  out.grey_colors.assign(indices.size(), kGrey);
  out.spacing_mm = surface_spacing_mm(out.points);
  return out;
}

namespace {

// A polyline through `points` in the view's pixels; nothing for fewer than two finite points.
std::string polyline_svg(const google::protobuf::RepeatedPtrField<v1::Vec3>& points,
                         const ViewProjection& view, const char* css_class) {
  std::ostringstream coords;
  int drawn = 0;
  for (const v1::Vec3& p : points) {
    const Vec3 v = to_vec(p);
    if (!v.allFinite()) continue;
    const Eigen::Vector2d px = view.to_pixel(v);
    if (drawn++ > 0) coords << ' ';
    coords << svg_number(px.x()) << ',' << svg_number(px.y());
  }
  if (drawn < 2) return "";
  std::ostringstream svg;
  svg << "<polyline class='" << css_class << "' points='" << coords.str() << "'/>";
  return svg.str();
}

// Each measured trim edge: the CAD edge (dashed) and the scan's edge, where a quality engineer
// reads overhang or draw-in against the colours. Bounded like the bend labels, per flange.
std::string trim_edges_overlay(const v1::InspectionReport& report, const ViewProjection& view,
                               const ReportSettings& settings) {
  std::string overlay;
  int drawn = 0;
  for (const v1::Segment& segment : report.segments()) {
    if (drawn >= settings.max_bend_labels) break;
    // Reports written before trim_edges carry the free edge alone.
    const auto draw = [&](const v1::EdgeDeviation& e) {
      overlay += polyline_svg(e.cad_edge(), view, "cadedge");
      overlay += polyline_svg(e.scan_edge(), view, "scanedge");
    };
    if (segment.trim_edges_size() > 0)
      for (const v1::EdgeDeviation& e : segment.trim_edges()) draw(e);
    else if (segment.has_edge_deviation_mm())
      draw(segment.edge_deviation_mm());
    else
      continue;
    ++drawn;
  }
  return overlay;
}

}  // namespace

analysis::Expected<std::string> deviation_views_html(const v1::InspectionReport& report,
                                                     const DrawCloud& cloud,
                                                     const ReportSettings& settings) {
  if (cloud.points.empty()) return missing_picture(settings);
  constexpr ViewKind kKinds[] = {ViewKind::kTop, ViewKind::kFront, ViewKind::kSide,
                                 ViewKind::kIsometric};
  constexpr std::size_t kCount = std::size(kKinds);
  // The views are independent: worker w draws views w, w + T, ...; each result has its own
  // slot, and the page joins them in a fixed order, so the thread count changes nothing.
  std::vector<analysis::Expected<std::string>> svgs(kCount, analysis::fail("not rendered"));
  const auto draw = [&](std::size_t first, std::size_t stride) {
    for (std::size_t i = first; i < kCount; i += stride) {
      const ViewProjection view = fit_view(cloud.points, kKinds[i], view_settings(settings));
      svgs[i] = view_svg(cloud.points, cloud.deviation_colors, cloud.spacing_mm, view, settings,
                         trim_edges_overlay(report, view, settings),
                         std::string("deviation, ") + view_name(kKinds[i]) + " view");
    }
  };
  const std::size_t workers = std::min<std::size_t>(
      kCount, settings.threads > 0 ? static_cast<std::size_t>(settings.threads)
                                   : std::max(1u, std::thread::hardware_concurrency()));
  std::vector<std::thread> pool;
  for (std::size_t w = 1; w < workers; ++w) pool.emplace_back(draw, w, workers);
  draw(0, workers);
  for (auto& t : pool) t.join();

  std::string html = "<div class='views'>";
  for (std::size_t i = 0; i < kCount; ++i) {
    if (!svgs[i]) return svgs[i].error();
    html += "<figure class='view'>" + *svgs[i] + "<figcaption>" + view_name(kKinds[i]) +
            " view</figcaption></figure>";
  }
  return html + "</div>";
}

std::pair<Vec3, Vec3> bend_axis_extent(const v1::Bend& bend, const std::vector<Vec3>& points) {
  const Vec3 p0 = to_vec(bend.axis_point());
  Vec3 dir = to_vec(bend.axis_direction());
  if (!(dir.norm() > 0) || !dir.allFinite()) dir = Vec3::UnitY();
  dir.normalize();
  Eigen::AlignedBox3d box;
  for (const auto& p : points)
    if (p.allFinite()) box.extend(p);
  const double size = box.isEmpty() ? 100.0 : box.diagonal().norm();
  const double near = std::max(3.0 * bend.radius_mm(), 0.05 * size);
  double t_min = std::numeric_limits<double>::infinity(), t_max = -t_min;
  for (const auto& p : points) {
    const Vec3 d = p - p0;
    const double t = d.dot(dir);
    if ((d - t * dir).squaredNorm() > near * near) continue;
    t_min = std::min(t_min, t);
    t_max = std::max(t_max, t);
  }
  if (!(t_min < t_max)) t_min = -0.15 * size, t_max = 0.15 * size;
  return {p0 + t_min * dir, p0 + t_max * dir};
}

analysis::Expected<std::string> bends_figure_html(const v1::InspectionReport& report,
                                                  const DrawCloud& cloud,
                                                  const ReportSettings& settings) {
  if (cloud.points.empty()) return missing_picture(settings);
  const ViewProjection view = fit_view(cloud.points, ViewKind::kIsometric, view_settings(settings));
  std::ostringstream overlay;
  // Each axis scans the drawn points once; the cap bounds the work for a hostile report.
  const int drawn = std::min(report.bends_size(), settings.max_bend_labels);
  for (int k = 0; k < drawn; ++k) {
    const v1::Bend& bend = report.bends(k);
    const auto [a, b] = bend_axis_extent(bend, cloud.points);
    const Eigen::Vector2d pa = view.to_pixel(a), pb = view.to_pixel(b);
    const char* state = !bend.measured() ? "nm" : bend.pass() ? "ok" : "ng";
    overlay << "<line class='axis " << state << "' x1='" << svg_number(pa.x()) << "' y1='"
            << svg_number(pa.y()) << "' x2='" << svg_number(pb.x()) << "' y2='"
            << svg_number(pb.y()) << "'/>";
    // The label sits at the axis end nearer the top of the picture, pushed outwards.
    const Eigen::Vector2d end = pa.y() < pb.y() ? pa : pb;
    const Eigen::Vector2d at = end + 12.0 * (end - 0.5 * (pa + pb)).normalized();
    overlay << "<g class='blabel " << state << "'><circle cx='" << svg_number(at.x()) << "' cy='"
            << svg_number(at.y()) << "' r='11'/><text x='" << svg_number(at.x()) << "' y='"
            << svg_number(at.y() + 4) << "' text-anchor='middle'>B" << bend.id() << "</text></g>";
  }
  auto svg = view_svg(cloud.points, cloud.grey_colors, cloud.spacing_mm, view, settings,
                      overlay.str(), "bends labelled on the isometric view");
  if (!svg) return svg.error();
  return "<figure class='view'>" + *svg +
         "<figcaption>Bend axes, isometric view (green: pass, red: fail, grey: not "
         "measured)</figcaption></figure>";
}

}  // namespace springscan::report
