// springscan report: renders the HTML inspection report again from a saved report.
#include <google/protobuf/util/json_util.h>

#include <filesystem>
#include <system_error>

#include "analysis/io/file_io.hpp"
#include "analysis/io/point_io.hpp"
#include "cli/cli_common.hpp"
#include "report/report_html.hpp"

namespace springscan::cli {
namespace {

namespace fs = std::filesystem;

// report.pb (binary) or report.json (protobuf's JSON mapping), by extension.
analysis::Expected<v1::InspectionReport> load_report(const fs::path& path) {
  auto bytes = analysis::read_file_bytes(path.string());
  if (!bytes) return bytes.error();
  v1::InspectionReport report;
  if (path.extension() == ".json") {
    const auto status = google::protobuf::util::JsonStringToMessage(*bytes, &report);
    if (!status.ok())
      return analysis::fail(path.string() +
                            ": not an InspectionReport in JSON: " + std::string(status.message()));
  } else if (!report.ParseFromString(*bytes)) {
    return analysis::fail(path.string() + ": not a binary InspectionReport (" +
                          std::to_string(bytes->size()) + " bytes)");
  }
  return report;
}

// The deviation cloud: --cloud FILE (must load), else deviation.ply beside the report (used
// when present and readable; otherwise the page says why the picture is missing).
analysis::Expected<analysis::PointCloud> load_cloud(const ArgParser& args,
                                                    const fs::path& report_path,
                                                    report::ReportSettings& settings,
                                                    const Logger& logger) {
  if (args.has("cloud")) return analysis::read_point_cloud(args.get("cloud"));
  const fs::path beside = report_path.parent_path() / "deviation.ply";
  std::error_code ec;
  if (!fs::exists(beside, ec)) {
    settings.missing_cloud_note =
        "deviation.ply was not found beside " + report_path.filename().string();
    logger.warning(settings.missing_cloud_note + ": rendering without the pictures");
    return analysis::PointCloud{};
  }
  auto cloud = analysis::read_point_cloud(beside.string());
  if (!cloud) {
    settings.missing_cloud_note = "deviation.ply could not be read (" + cloud.message() + ")";
    logger.warning(settings.missing_cloud_note);
    return analysis::PointCloud{};
  }
  return cloud;
}

}  // namespace

int report_main(int argc, char** argv) {
  ArgParser args("report", "REPORT.pb [--out report.html]",
                 "Renders the HTML inspection report again from a saved report (report.pb, or\n"
                 "report.json). The deviation pictures are drawn from deviation.ply beside the\n"
                 "report; without it the page still renders and says the pictures are missing.");
  args.add_option("out", "FILE", "where to write the page (default: report.html beside REPORT)");
  args.add_option("cloud", "FILE", "the deviation cloud (default: deviation.ply beside REPORT)");
  Logger logger;
  switch (args.parse(argc, argv, 2)) {
    case ArgParser::Outcome::kHelpShown:
      return kExitOk;
    case ArgParser::Outcome::kUsageError:
      return fail_with("report", args.error(), kExitUsage);
    case ArgParser::Outcome::kRun:
      break;
  }
  if (!args.configure_logger(logger)) return fail_with("report", args.error(), kExitUsage);
  if (args.positionals().size() != 1)
    return fail_with("report", "expects one REPORT file (see springscan report --help)",
                     kExitUsage);
  const fs::path report_path = args.positionals().front();
  auto report = load_report(report_path);
  if (!report) return fail_with("report", report.message(), kExitUsage);
  report::ReportSettings settings;
  auto cloud = load_cloud(args, report_path, settings, logger);
  if (!cloud) return fail_with("report", cloud.message(), kExitUsage);
  const fs::path out = args.has("out") ? fs::path(args.get("out"))
                                       : report_path.parent_path() / report::kReportHtmlName;
  auto written = report::write_report_html(out, *report, *cloud, settings);
  if (!written) return fail_with("report", written.message(), kExitAnalysisFailed);
  logger.info("wrote " + written->string());
  return kExitOk;
}

}  // namespace springscan::cli
