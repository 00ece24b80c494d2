#include "report/inspection_files.hpp"

#include <google/protobuf/util/json_util.h>

#include <algorithm>
#include <cmath>
#include <ctime>
#include <filesystem>
#include <system_error>

#include "analysis/deviation/deviation.hpp"
#include "analysis/io/point_io.hpp"
#include "report/report_html.hpp"

namespace springscan::report {

using namespace springscan::analysis;
namespace {

std::string join(const std::string& dir, const char* name) {
  return (std::filesystem::path(dir) / name).string();
}

}  // namespace

double deviation_color_scale_mm(const v1::InspectionReport& report) {
  const auto& deviation = report.deviation();
  if (deviation.color_scale_mm() > 0.0 && std::isfinite(deviation.color_scale_mm())) {
    return deviation.color_scale_mm();
  }
  if (deviation.tolerance_mm() > 0.0 && std::isfinite(deviation.tolerance_mm())) {
    return 3.0 * deviation.tolerance_mm();
  }
  return 1.0;
}

Expected<std::string> report_to_json(const v1::InspectionReport& report) {
  google::protobuf::util::JsonPrintOptions options;
  options.add_whitespace = true;
  options.always_print_primitive_fields = true;
  options.preserve_proto_field_names = true;
  std::string json;
  const auto status = google::protobuf::util::MessageToJsonString(report, &json, options);
  if (!status.ok()) return fail("cannot print the report as JSON: " + status.ToString());
  return json;
}

Expected<v1::InspectionReport> report_from_json(std::string_view json) {
  v1::InspectionReport report;
  const auto status = google::protobuf::util::JsonStringToMessage(std::string(json), &report);
  if (!status.ok()) return fail("cannot parse the report JSON: " + status.ToString());
  return report;
}

Expected<std::string> format_deviation_ply(const PointCloud& cloud, double scale_mm) {
  Surface deviation;
  deviation.cloud = cloud;
  if (deviation.cloud.has_scalars()) {
    deviation.cloud.colors.resize(deviation.cloud.scalars.size());
    for (std::size_t i = 0; i < deviation.cloud.scalars.size(); ++i) {
      deviation.cloud.colors[i] = deviation_color(deviation.cloud.scalars[i], scale_mm);
    }
  }
  PointWriteOptions ply;
  ply.scalar_name = "signed_deviation_mm";
  return format_ply(deviation, ply);
}

Expected<InspectionFiles> write_inspection_files(const std::string& dir,
                                                 const InspectionOutcome& outcome) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) return fail("cannot create report directory '" + dir + "': " + ec.message());

  auto json = report_to_json(outcome.report);
  if (!json) return json.error();
  if (auto written = write_file_atomically(join(dir, "report.json"), *json); !written) {
    return written.error();
  }

  const std::string ply_path = join(dir, "deviation.ply");
  auto ply =
      format_deviation_ply(outcome.deviation_cloud, deviation_color_scale_mm(outcome.report));
  if (!ply) return ply.error().prepend(ply_path + ": ");
  if (auto written = write_file_atomically(ply_path, *ply); !written) return written.error();

  // The compensation a tool designer loads: vectors as CSV and PLY, and the CAD tessellation
  // moved by them (docs/matching.md "Compensation").
  if (auto written = write_file_atomically(join(dir, "compensation.csv"),
                                           format_compensation_csv(outcome.compensation));
      !written)
    return written.error();
  if (auto written = write_file_atomically(join(dir, "compensation.ply"),
                                           format_compensation_ply(outcome.compensation));
      !written)
    return written.error();
  if (!outcome.compensated_surface.triangles.empty()) {
    Surface surface;
    surface.cloud.points = outcome.compensated_surface.vertices;
    surface.triangles = outcome.compensated_surface.triangles;
    auto stl = format_stl(surface);
    if (!stl) return stl.error().prepend("compensated-surface.stl: ");
    if (auto written = write_file_atomically(join(dir, "compensated-surface.stl"), *stl); !written)
      return written.error();
  }

  InspectionFiles files;
  auto html = write_report_html_in_dir(dir, outcome.report, outcome.deviation_cloud);
  if (!html) files.html_error = html.message();

  // Last: a present report.pb means the other two files are complete (the daemon relies on it).
  std::string pb;
  if (!outcome.report.SerializeToString(&pb)) return fail("cannot serialize the report");
  if (auto written = write_file_atomically(join(dir, "report.pb"), pb); !written) {
    return written.error();
  }
  return files;
}

void stamp_report(v1::InspectionReport& report) {
  report.set_software_version(SPRINGSCAN_VERSION);
  if (!report.created_utc().empty()) return;
  const std::time_t now = std::time(nullptr);
  std::tm utc{};
  gmtime_r(&now, &utc);
  char text[32];
  std::strftime(text, sizeof text, "%Y-%m-%dT%H:%M:%SZ", &utc);
  report.set_created_utc(text);
}

Expected<v1::InspectionReport> read_report_pb(const std::string& path) {
  auto bytes = read_file_bytes(path);
  if (!bytes) return bytes.error();
  v1::InspectionReport report;
  if (!report.ParseFromString(*bytes)) {
    return fail(path + ": not a springscan InspectionReport (protobuf parse failed, " +
                std::to_string(bytes->size()) + " bytes)");
  }
  return report;
}

}  // namespace springscan::report
