// springscan match: the correspondences of paper section 5 on their own, so the matching can
// be used and checked outside the pipeline. Output: one CSV line per pair.
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

#include "analysis/io/file_io.hpp"
#include "analysis/io/point_io.hpp"
#include "analysis/matching/deformation_field.hpp"
#include "analysis/preprocess/kcenter.hpp"
#include "cli/cli_common.hpp"

namespace springscan::cli {
namespace {

constexpr const char* kName = "match";

// The k-center reduction of the paper (section 2) with radius w, or all points when w = 0.
// `original` maps each kept point back to its index in the file.
analysis::Expected<std::vector<analysis::Vec3>> reduce(const std::vector<analysis::Vec3>& points,
                                                       double w,
                                                       std::vector<std::uint32_t>& original) {
  original.clear();
  if (w <= 0.0) {
    for (std::uint32_t i = 0; i < points.size(); ++i) original.push_back(i);
    return points;
  }
  analysis::KCenterSettings settings;
  settings.radius_mm = w;
  auto reduced = analysis::kcenter_reduce(points, settings);
  if (!reduced) return reduced.error();
  std::vector<analysis::Vec3> kept;
  kept.reserve(reduced->centers.size());
  for (const auto i : reduced->centers) {
    kept.push_back(points[i]);
    original.push_back(i);
  }
  return kept;
}

// Pair indices refer to the files' points, also after the reduction.
std::string format_pairs(const analysis::DeformationField& field,
                         const std::vector<std::uint32_t>& model_index,
                         const std::vector<std::uint32_t>& scan_index) {
  std::string out = "model_index,scan_index,squared_distance_mm2\n";
  out.reserve(out.size() + field.vectors.size() * 32);
  char line[96];
  for (const auto& v : field.vectors) {
    std::snprintf(line, sizeof line, "%u,%u,%.17g\n", model_index[v.model_index],
                  scan_index[v.scan_index], v.squared_distance_mm2);
    out += line;
  }
  return out;
}

double ms_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
      .count();
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
                    ? (field.optimality_certified ? ", optimality certified" : ", NOT certified")
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
  args.add_option("reduce-radius", "MM",
                  "k-center reduction of both clouds with radius w first (paper: 10 mm); "
                  "indices still refer to the files");
  Logger log;
  if (auto exit_code = args.start(argc, argv, log)) return *exit_code;
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
  double w = 0.0;
  if (args.has("reduce-radius")) {
    const auto radius = args.get_number("reduce-radius");
    if (!radius || !(*radius > 0.0) || !std::isfinite(*radius)) {
      return fail_with(
          kName, "--reduce-radius " + args.get("reduce-radius") + ": expected a radius > 0 in mm",
          kExitUsage);
    }
    w = *radius;
  }
  const auto read_start = std::chrono::steady_clock::now();
  const auto model = analysis::read_point_cloud(args.get("model"));
  if (!model) return fail_with(kName, model.message(), kExitUsage);
  const auto scan = analysis::read_point_cloud(args.get("scan"));
  if (!scan) return fail_with(kName, scan.message(), kExitUsage);

  const double read_ms = ms_since(read_start);
  const auto start = std::chrono::steady_clock::now();
  std::vector<std::uint32_t> model_index, scan_index;
  const auto model_points = reduce(model->points, w, model_index);
  if (!model_points)
    return fail_with(kName, args.get("model") + ": " + model_points.message(), kExitAnalysisFailed);
  const auto scan_points = reduce(scan->points, w, scan_index);
  if (!scan_points)
    return fail_with(kName, args.get("scan") + ": " + scan_points.message(), kExitAnalysisFailed);
  const auto field = analysis::deformation_field(*model_points, *scan_points, settings);
  const double ms = ms_since(start);
  if (!field) return fail_with(kName, field.message(), kExitAnalysisFailed);
  const auto write_start = std::chrono::steady_clock::now();
  if (const auto written = analysis::write_file_atomically(
          args.get("out"), format_pairs(*field, model_index, scan_index));
      !written) {
    return fail_with(kName, written.message(), kExitAnalysisFailed);
  }
  // Where a whole command's time goes besides the matching (docs/performance.md "The whole
  // command").
  char timings[128];
  std::snprintf(timings, sizeof timings, "read %.1f ms, write %.1f ms", read_ms,
                ms_since(write_start));
  log.debug(timings);
  log.info(summary(*field, ms));
  return kExitOk;
}

}  // namespace springscan::cli
