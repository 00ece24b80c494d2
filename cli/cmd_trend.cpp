// springscan trend: statistical process control over many reports (report/trend.hpp), drawn
// as one self-contained HTML page (report/trend_html.hpp).
#include <chrono>
#include <filesystem>

#include "analysis/io/file_io.hpp"
#include "cli/cli_common.hpp"
#include "report/trend.hpp"
#include "report/trend_html.hpp"

namespace springscan::cli {

int trend_main(int argc, char** argv) {
  ArgParser args("trend", "REPORTS_DIR... [--out trend.html]",
                 "Reads many reports (a station's report store, a folder of report.pb files, or\n"
                 "single report.pb files) and draws, per part and characteristic (each bend's\n"
                 "springback, the deviation max |d| and p95), an individuals chart with its\n"
                 "moving range, the tolerance and control limits, Cp and Cpk, and the points\n"
                 "that break a Western Electric rule; a table lists the characteristics by Cpk.");
  args.add_option("out", "FILE", "where to write the page (default: trend.html)");
  args.add_option("title", "TEXT", "the page title (default: springscan trend)");
  Logger logger;
  if (auto done = args.start(argc, argv, logger)) return *done;
  if (args.positionals().empty())
    return fail_with("trend", "expects at least one REPORTS_DIR (see springscan trend --help)",
                     kExitUsage);
  const auto start = std::chrono::steady_clock::now();
  auto input = report::read_reports(args.positionals());
  if (!input) return fail_with("trend", input.message(), kExitUsage);
  for (const auto& skipped : input->skipped) logger.warning("skipped " + skipped);
  const auto characteristics = report::collect_characteristics(input->reports);
  report::TrendPageInfo info;
  if (args.has("title")) info.title = args.get("title");
  info.sources = args.positionals();
  info.reports = input->reports.size();
  info.decisions = report::decision_counts(input->reports);
  info.skipped = input->skipped.size();
  info.first_utc = input->reports.front().created_utc();
  info.last_utc = input->reports.back().created_utc();
  const std::string html = report::render_trend_html(characteristics, info);
  const std::string out = args.get("out", "trend.html");
  auto written = analysis::write_file_atomically(out, html);
  if (!written) return fail_with("trend", written.message(), kExitAnalysisFailed);
  const double ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  logger.info("wrote " + out + ": " + std::to_string(characteristics.size()) +
              " characteristics from " + std::to_string(info.reports) + " reports in " +
              std::to_string(static_cast<long long>(ms)) + " ms");
  return kExitOk;
}

}  // namespace springscan::cli
