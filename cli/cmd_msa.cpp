// springscan msa: the gauge capability studies (report/msa.hpp) over report folders as `springscan
// trend` reads them, written as one self-contained HTML page (report/msa_html.hpp) and JSON.
#include <cstdio>
#include <string>

#include "analysis/io/file_io.hpp"
#include "cli/cli_common.hpp"
#include "report/msa.hpp"
#include "report/msa_html.hpp"
#include "report/trend.hpp"

namespace springscan::cli {
namespace {

constexpr const char* kName = "msa";

/// A figure with 2 decimals, or "-" where it is not defined (no tolerance, no spread).
std::string figure(bool has, double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.2f", value);
  return has ? text : "-";
}

void print_type1(const v1::MsaType1Study& study) {
  for (const auto& c : study.characteristics())
    std::printf("%s: n %d, mean %.5f, s %.5f, bias %+.5f (p %.3f), Cg %s, Cgk %s: %s\n",
                c.name().c_str(), c.n(), c.mean(), c.stddev(), c.bias(), c.bias_p(),
                figure(c.has_cg(), c.cg()).c_str(), figure(c.has_cgk(), c.cgk()).c_str(),
                c.capable() ? "capable" : "NOT capable");
  std::printf("type 1: %s\n", study.capable() ? "capable" : "NOT capable");
}

void print_type3(const v1::MsaType3Study& study) {
  for (const auto& c : study.characteristics())
    std::printf("%s: %d parts x %d trials, EV %.5f, PV %.5f, %%GRR %s of T, %s of TV, ndc %s: %s\n",
                c.name().c_str(), c.parts(), c.trials(), c.ev(), c.pv(),
                figure(c.has_grr_pct_tolerance(), c.grr_pct_tolerance()).c_str(),
                figure(c.has_grr_pct_total(), c.grr_pct_total()).c_str(),
                figure(c.has_ndc(), c.ndc()).c_str(), c.verdict().c_str());
  std::printf("type 3: %s\n", study.acceptable() ? "acceptable" : "NOT acceptable");
}

/// The study settings from --tolerance NAME=T and --characteristic NAME.
analysis::Expected<report::MsaSettings> study_settings(const ArgParser& args) {
  report::MsaSettings settings;
  for (const std::string& text : args.get_all("tolerance")) {
    auto tolerance = report::parse_tolerance(text);
    if (!tolerance) return tolerance.error();
    settings.tolerances[tolerance->first] = tolerance->second;
  }
  settings.only = args.get_all("characteristic");
  return settings;
}

/// Writes the JSON (when asked) and the page; both are computed before anything is written.
int write_outputs(const ArgParser& args, const std::string& html,
                  const google::protobuf::Message& study) {
  if (args.has("json")) {
    auto json = report::msa_to_json(study);
    if (!json) return fail_with(kName, json.message(), kExitAnalysisFailed);
    auto written = analysis::write_file_atomically(args.get("json"), *json);
    if (!written) return fail_with(kName, written.message(), kExitUsage);
  }
  auto written = analysis::write_file_atomically(args.get("out", "msa.html"), html);
  if (!written) return fail_with(kName, written.message(), kExitUsage);
  return kExitOk;
}

}  // namespace

int msa_main(int argc, char** argv) {
  ArgParser args(
      kName,
      "type1 REPORTS... --reference REF.json --out msa.html [--json msa.json]\n"
      "       springscan msa type3 REPORTS... --out msa.html [--json msa.json]",
      "Gauge capability studies over report folders (as springscan trend reads them).\n"
      "type1: at least 25 reports of one reference part; per characteristic named in\n"
      "REF.json ({\"bend 1 springback\": 0.42, ...}) the mean, s, bias and its t-test,\n"
      "Cg = 0.2 T / (6 s), Cgk = (0.1 T - |bias|) / (3 s); a run chart and a histogram.\n"
      "type3: at least 5 parts x 2 trials, grouped by input.part_serial (analyze\n"
      "--serial), balanced; one-way ANOVA: EV, PV, GRR, %GRR of T and of the total\n"
      "variation, ndc. T from the reports (2 x the angle tolerance for springback).\n"
      "Exit 1, nothing written, when the reports cannot make the study.");
  args.add_option("reference", "REF.json", "type1: reference value per characteristic name");
  args.add_option("out", "FILE", "the HTML page (default: msa.html)");
  args.add_option("json", "FILE", "also the figures as JSON");
  args.add_option("tolerance", "NAME=T", "tolerance width T of a characteristic (repeatable)");
  args.add_option("characteristic", "NAME", "study only this characteristic (repeatable)");
  args.add_option("title", "TEXT", "the page title");
  Logger logger;
  if (auto done = args.start(argc, argv, logger)) return *done;
  const auto& positionals = args.positionals();
  if (positionals.empty() || (positionals[0] != "type1" && positionals[0] != "type3"))
    return fail_with(kName, "expects type1 or type3 first (see springscan msa --help)", kExitUsage);
  const bool type1 = positionals[0] == "type1";
  if (positionals.size() < 2) return fail_with(kName, "expects REPORTS... folders", kExitUsage);
  if (type1 && !args.has("reference"))
    return fail_with(kName, "type1 needs --reference REF.json", kExitUsage);
  auto settings = study_settings(args);
  if (!settings) return fail_with(kName, settings.message(), kExitUsage);
  const std::vector<std::string> sources(positionals.begin() + 1, positionals.end());
  auto input = report::read_reports(sources);
  if (!input) return fail_with(kName, input.message(), kExitUsage);
  for (const auto& skipped : input->skipped) logger.warning("skipped " + skipped);
  report::MsaPageInfo info{args.get("title"), sources, input->reports.front().created_utc(),
                           input->reports.back().created_utc()};
  if (type1) {
    auto text = analysis::read_file_bytes(args.get("reference"));
    if (!text) return fail_with(kName, text.message(), kExitUsage);
    auto references = report::parse_references(*text);
    if (!references)
      return fail_with(kName, args.get("reference") + ": " + references.message(), kExitUsage);
    auto study = report::type1_study(input->reports, *references, *settings);
    if (!study) return fail_with(kName, study.message(), kExitAnalysisFailed);
    if (const int code = write_outputs(args, report::render_type1_html(*study, info), *study))
      return code;
    if (!args.has("quiet")) print_type1(*study);
    return kExitOk;
  }
  auto study = report::type3_study(input->reports, *settings);
  if (!study) return fail_with(kName, study.message(), kExitAnalysisFailed);
  if (const int code = write_outputs(args, report::render_type3_html(*study, info), *study))
    return code;
  if (!args.has("quiet")) print_type3(*study);
  return kExitOk;
}

}  // namespace springscan::cli
