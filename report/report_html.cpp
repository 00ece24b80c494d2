#include "report/report_html.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "analysis/io/file_io.hpp"
#include "report/figures.hpp"
#include "report/html_text.hpp"
#include "report/plots.hpp"
#include "report/report_sections.hpp"
#include "report/report_style.hpp"

namespace springscan::report {
namespace {

// The tolerance the colour map marks: the one the verdict judged the surface by, which the
// report keeps in deviation.tolerance_mm (analysis/messages/verdict_proto.hpp).
double tolerance_of(const v1::InspectionReport& report) {
  return std::max(report.deviation().tolerance_mm(), 0.0);
}

// |deviation| drawn full blue or red: the setting, else the rule deviation.ply is coloured
// by (report/inspection_files.hpp deviation_color_scale_mm: the report's color_scale_mm, else
// 3 x tolerance, else 1 mm), so the page and the PLY agree.
double color_scale_of(const v1::InspectionReport& report, const ReportSettings& settings) {
  if (settings.color_scale_mm > 0 && std::isfinite(settings.color_scale_mm))
    return settings.color_scale_mm;
  const double stored = report.deviation().color_scale_mm();
  if (stored > 0 && std::isfinite(stored)) return stored;
  const double tolerance = report.deviation().tolerance_mm();
  if (tolerance > 0 && std::isfinite(tolerance)) return 3.0 * tolerance;
  return 1.0;
}

analysis::Expected<std::string> deviation_section(const v1::InspectionReport& report,
                                                  const DrawCloud& cloud, double scale_mm,
                                                  const ReportSettings& settings) {
  auto views = deviation_views_html(report, cloud, settings);
  if (!views) return views.error();
  return "<section id='deviation'><h2>Surface deviation</h2><div class='grid2'>" +
         deviation_table(report.deviation()) +
         "<div><p class='note'>Signed distance of each scan point to the CAD surface after the "
         "global best fit, drawn from " +
         std::to_string(cloud.points.size()) +
         " points of the scan. Green lies within the tolerance; blue is below the CAD surface "
         "(against its outward normal), red above. A flange coloured blue at one end and red at "
         "the other is turned: look at the bend table. A measured trim edge is drawn twice: "
         "where the CAD puts it (dashed) and where the scan's edge is (purple).</p></div></div>" +
         "<div class='colorbar-wrap'>" + color_bar_svg(scale_mm, tolerance_of(report), 1000) +
         "</div>" + *views + "</section>";
}

analysis::Expected<std::string> bends_section(const v1::InspectionReport& report,
                                              const DrawCloud& cloud,
                                              const ReportSettings& settings) {
  if (report.bends_size() == 0)
    return std::string(
        "<section id='bends' class='printbreak'><h2>Bends and springback</h2><p class='note'>"
        "No bends in this part.</p></section>");
  auto figure = bends_figure_html(report, cloud, settings);
  if (!figure) return figure.error();
  return "<section id='bends' class='printbreak'><h2>Bends and springback</h2>" +
         bend_table(report) + "<div class='grid2'>" + *figure + segment_table(report) +
         "</div></section>";
}

std::string global_fit_section(const v1::InspectionReport& report) {
  const auto& registration = report.settings().registration();
  ErrorPlotSettings plot;
  if (registration.has_error_ratio_stop()) plot.ratio_stop = registration.error_ratio_stop();
  return "<section id='fit' class='keep'><h2>Global best fit</h2><div class='grid2'>" +
         global_fit_table(report) + reduction_table(report.reduction()) + "</div>" + "<figure>" +
         error_progression_svg({report.global_fit().error_history().begin(),
                                report.global_fit().error_history().end()},
                               plot) +
         "<figcaption>Error progression of the ICP fit: E(i) and the quotient E(i)/E(i-1), "
         "after the paper's Figure 6b. A quotient near 1 means further iterations no longer "
         "improve the fit.</figcaption></figure></section>";
}

analysis::Expected<std::string> compensation_section(const v1::InspectionReport& report,
                                                     const DrawCloud& cloud,
                                                     const ReportSettings& settings) {
  auto figure = compensation_figure_html(report, cloud, settings);
  if (!figure) return figure.error();
  return "<section id='compensation' class='keep printbreak'><h2>Deformation and compensation</h2>"
         "<div class='grid2'>" +
         *figure + deformation_table(report) + "</div></section>";
}

}  // namespace

analysis::Expected<std::string> render_report_html(const v1::InspectionReport& report,
                                                   const analysis::PointCloud& deviation_cloud,
                                                   const ReportSettings& settings) {
  if (!deviation_cloud.attributes_consistent())
    return analysis::fail(
        "render_report_html: the deviation cloud's attributes disagree with "
        "its " +
        std::to_string(deviation_cloud.size()) + " points");
  const double scale_mm = color_scale_of(report, settings);
  const DrawCloud cloud = make_draw_cloud(deviation_cloud, scale_mm, settings);
  auto deviation = deviation_section(report, cloud, scale_mm, settings);
  if (!deviation) return deviation.error();
  auto bends = bends_section(report, cloud, settings);
  if (!bends) return bends.error();
  auto compensation = compensation_section(report, cloud, settings);
  if (!compensation) return compensation.error();

  std::string html;
  html.reserve(1 << 20);
  html +=
      "<!DOCTYPE html>\n<html lang='en'><head><meta charset='utf-8'>"
      "<meta name='viewport' content='width=device-width, initial-scale=1'>"
      "<title>Inspection report " +
      escape_html(report.input().part_id()) + "</title><style>";
  html += report_css();
  html += "</style></head><body>";
  html += header_html(report);
  html += *deviation + *bends + global_fit_section(report) + *compensation;
  html +=
      "<section id='timings' class='keep'><h2>Statistics and stage timings</h2>"
      "<div class='grid2'>" +
      timings_table(report.timings_ms()) + input_table(report) + "</div></section>";
  html += warnings_html(report) + footer_html(report) + "</body></html>\n";
  return html;
}

analysis::Expected<std::filesystem::path> write_report_html(
    const std::filesystem::path& path, const v1::InspectionReport& report,
    const analysis::PointCloud& deviation_cloud, const ReportSettings& settings) {
  auto html = render_report_html(report, deviation_cloud, settings);
  if (!html) return html.error();
  // A reader (a browser, the daemon's report store) sees the old page or the whole new one.
  auto written = analysis::write_file_atomically(path.string(), *html);
  if (!written) return written.error();
  return path;
}

analysis::Expected<std::filesystem::path> write_report_html_in_dir(
    const std::filesystem::path& dir, const v1::InspectionReport& report,
    const analysis::PointCloud& deviation_cloud, const ReportSettings& settings) {
  return write_report_html(dir / kReportHtmlName, report, deviation_cloud, settings);
}

}  // namespace springscan::report
