// springscan match: the correspondences of paper section 5 on their own, so the matching can
// be used and checked outside the pipeline. Output: one CSV line per pair.
#include <chrono>
#include <cstdio>
#include <string>

#include "analysis/deformation_field.hpp"
#include "analysis/file_io.hpp"
#include "analysis/point_io.hpp"
#include "cli/cli_common.hpp"

namespace springscan::cli {
namespace {

constexpr const char* kName = "match";

std::string format_pairs(const analysis::DeformationField& field) {
  std::string out = "model_index,scan_index,squared_distance_mm2\n";
  out.reserve(out.size() + field.vectors.size() * 32);
  char line[96];
  for (const auto& v : field.vectors) {
    std::snprintf(line, sizeof line, "%u,%u,%.17g\n", v.model_index, v.scan_index,
                  v.squared_distance_mm2);
    out += line;
  }
  return out;
}

std::string summary(const analysis::DeformationField& field, double ms) {
  char text[256];
  std::snprintf(text, sizeof text,
                "%zu pairs (%s), model %zu, scan %zu points, total %.6g mm^2, coverage %.3f "
                "(nearest neighbour %.3f)%s, %.1f ms",
                field.vectors.size(), analysis::to_string(field.method), field.model_points,
                field.scan_points, field.total_cost_mm2, field.coverage,
                field.nearest_neighbor_coverage,
                field.method == analysis::CorrespondenceMethod::kMinCostMatching
                    ? (field.optimality_certified ? ", optimality certified"
                                                  : ", NOT certified")
                    : "",
                ms);
  return text;
}

}  // namespace

int match_main(int argc, char** argv) {
  ArgParser args(kName, "springscan match --model A --scan B --out pairs.csv [options]",
                 "Pairs the points of two clouds (any point format) one-to-one by the minimum "
                 "sum of squared distances (exact, with a dual certificate), or by nearest "
                 "neighbour. Writes model_index,scan_index,squared_distance_mm2 per pair.");
  args.add_option("model", "FILE", "model points (PLY, XYZ/CSV/TXT/PTS, STL)");
  args.add_option("scan", "FILE", "scan points, same frame as the model");
  args.add_option("out", "FILE", "the pairs as CSV");
  args.add_option("method", "NAME", "matching (default) or nearest");
  args.add_option("neighbors", "K", "candidate neighbours of the sparse solver (default 32)");
  Logger log;
  switch (args.parse(argc, argv, 2)) {
    case ArgParser::Outcome::kHelpShown: return kExitOk;
    case ArgParser::Outcome::kUsageError: return fail_with(kName, args.error(), kExitUsage);
    case ArgParser::Outcome::kRun: break;
  }
  if (!args.configure_logger(log)) return fail_with(kName, args.error(), kExitUsage);
  for (const char* required : {"model", "scan", "out"}) {
    if (!args.has(required)) {
      return fail_with(kName, std::string("--") + required + " is required", kExitUsage);
    }
  }
  analysis::DeformationFieldSettings settings;
  const std::string method = args.get("method", "matching");
  if (method == "nearest") {
    settings.method = analysis::CorrespondenceMethod::kNearestNeighbor;
  } else if (method != "matching") {
    return fail_with(kName, "--method " + method + ": expected matching or nearest", kExitUsage);
  }
  if (args.has("neighbors")) {
    const auto k = args.get_number("neighbors");
    if (!k || *k < 1 || *k > 1024 || *k != static_cast<int>(*k)) {
      return fail_with(kName, "--neighbors " + args.get("neighbors") + ": expected 1..1024",
                       kExitUsage);
    }
    settings.matching.candidate_neighbors = static_cast<int>(*k);
  }
  const auto model = analysis::read_point_cloud(args.get("model"));
  if (!model) return fail_with(kName, model.message(), kExitUsage);
  const auto scan = analysis::read_point_cloud(args.get("scan"));
  if (!scan) return fail_with(kName, scan.message(), kExitUsage);

  const auto start = std::chrono::steady_clock::now();
  const auto field = analysis::deformation_field(model->points, scan->points, settings);
  const double ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  if (!field) return fail_with(kName, field.message(), kExitAnalysisFailed);
  if (const auto written = analysis::write_file_atomically(args.get("out"), format_pairs(*field));
      !written) {
    return fail_with(kName, written.message(), kExitAnalysisFailed);
  }
  log.info(summary(*field, ms));
  return kExitOk;
}

}  // namespace springscan::cli
