#pragma once
// The report files of one inspection (DESIGN.md "The offline command"; docs/report-format.md):
//   DIR/report.json    the InspectionReport in protobuf's JSON mapping, .proto field names,
//                      every field printed (zeros too), pretty-printed
//   DIR/report.pb      the same message in protobuf binary
//   DIR/deviation.ply  the scan points in the CAD frame coloured by signed deviation, with the
//                      deviation itself as the vertex property `signed_deviation_mm`
//   DIR/report.html    the page a quality engineer opens (report_html.hpp)
// Every file is written atomically (file_io.hpp), report.pb last: when report.pb is there, the
// whole set is. `springscan analyze` and the daemon's report store both write through
// write_inspection_files, so the two leave the same files.

#include <string>
#include <string_view>

#include "analysis/core/expected.hpp"
#include "analysis/core/point_cloud.hpp"
#include "analysis/deviation/deviation.hpp"  // deviation_color, the colour map of deviation.ply
#include "analysis/inspection/pipeline.hpp"
#include "analysis/io/file_io.hpp"  // write_file_atomically, shared with the daemon's report store
#include "proto/springscan.pb.h"

namespace springscan::report {

using analysis::Expected;
using analysis::InspectionOutcome;
using analysis::PointCloud;

/// The scale deviation.ply is coloured with (analysis/deviation/deviation.hpp deviation_color):
/// report.deviation().color_scale_mm() when positive (the pipeline always records the scale it
/// used), else 3 times report.deviation().tolerance_mm() when positive, else 1 mm.
double deviation_color_scale_mm(const v1::InspectionReport& report);

/// report.json's text: the report in protobuf's JSON mapping with the .proto field names and
/// every primitive field printed, indented.
Expected<std::string> report_to_json(const v1::InspectionReport& report);

/// Parses report.json's text back (unknown fields are an error).
Expected<v1::InspectionReport> report_from_json(std::string_view json);

/// deviation.ply's bytes (binary PLY): the points of `cloud`, coloured by deviation_color at
/// `scale_mm` when the cloud has scalars (the signed deviations, also written as the vertex
/// property `signed_deviation_mm`), the points with the colours they have otherwise. The
/// daemon's report store writes the same bytes.
Expected<std::string> format_deviation_ply(const PointCloud& cloud, double scale_mm);

/// What write_inspection_files wrote beyond the files it guarantees.
struct InspectionFiles {
  /// Why report.html is missing ("" when it was written). The page is not part of the
  /// guaranteed set: a picture that cannot be drawn must not cost the PLC its result.
  std::string html_error;
};

/// Writes report.json, deviation.ply, report.html and report.pb into `dir` (created when
/// missing), each atomically, in that order. deviation.ply holds outcome.deviation_cloud with
/// colours from deviation_color at deviation_color_scale_mm(outcome.report) when the cloud has
/// scalars (the signed deviations), and the points alone otherwise (colours it already has are
/// then kept); an empty cloud (a scan that failed) gives a PLY without vertices, and a page
/// without pictures. Errors name the file and the reason; a page that could not be rendered is
/// not an error (InspectionFiles::html_error). Not thread-safe for the same `dir`.
Expected<InspectionFiles> write_inspection_files(const std::string& dir,
                                                 const InspectionOutcome& outcome);

/// Stamps what the analysis cannot know: software_version (this build's project version) and
/// created_utc (now, ISO 8601, when still empty). `springscan analyze` and springscand call it
/// before they write the files, so every report says which build made it and when.
void stamp_report(v1::InspectionReport& report);

/// Reads a report.pb written by write_inspection_files.
Expected<v1::InspectionReport> read_report_pb(const std::string& path);

}  // namespace springscan::report
