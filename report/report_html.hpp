#pragma once
// The HTML inspection report a quality engineer reads: one self-contained page
// (no external file, no network: pictures are inline SVG and data: URI PNGs) with the verdict
// and reasons on top, deviation colour maps, the bend table with the bends labelled on a
// picture, the global fit's error progression (paper, Figure 6b), compensation arrows,
// statistics and stage timings. Prints on A4. docs/report-html.md says how to read it.

#include <filesystem>
#include <string>

#include "analysis/core/expected.hpp"
#include "analysis/core/point_cloud.hpp"
#include "proto/springscan.pb.h"
#include "report/report_settings.hpp"

namespace springscan::report {

/// Renders the page. `deviation_cloud` holds the scan points in the CAD frame with scalars =
/// signed deviation in mm (the cloud of deviation.ply); it may be empty, and then the page
/// says the pictures are missing (settings.missing_cloud_note tells why). Every text taken
/// from the report is HTML-escaped. Errors: a cloud whose attributes disagree in size, or a
/// PNG that could not be encoded. Thread-safe: no shared state.
analysis::Expected<std::string> render_report_html(const v1::InspectionReport& report,
                                                   const analysis::PointCloud& deviation_cloud,
                                                   const ReportSettings& settings = {});

/// Renders the page and writes it to `path` atomically (analysis::write_file_atomically), so
/// a reader never sees half a report. Errors name the path and the cause.
analysis::Expected<std::filesystem::path> write_report_html(
    const std::filesystem::path& path, const v1::InspectionReport& report,
    const analysis::PointCloud& deviation_cloud, const ReportSettings& settings = {});

/// The file name of the report inside a report directory: "report.html".
inline constexpr const char* kReportHtmlName = "report.html";

/// Writes DIR/report.html (beside report.json, report.pb and deviation.ply). Errors as above.
analysis::Expected<std::filesystem::path> write_report_html_in_dir(
    const std::filesystem::path& dir, const v1::InspectionReport& report,
    const analysis::PointCloud& deviation_cloud, const ReportSettings& settings = {});

}  // namespace springscan::report
