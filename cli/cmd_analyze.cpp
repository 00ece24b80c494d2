// springscan analyze: the offline inspection (DESIGN.md "The offline command"): CAD (or a model
// point file) + scan in, report.json, report.pb and deviation.ply out.
#include <google/protobuf/io/tokenizer.h>
#include <google/protobuf/text_format.h>

#include <array>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "analysis/cad/model.hpp"
#include "analysis/cad/point_model.hpp"
#include "analysis/inspection/pipeline.hpp"
#include "analysis/io/file_io.hpp"
#include "analysis/io/point_io.hpp"
#include "analysis/io/sha256.hpp"
#include "analysis/messages/cad_model_proto.hpp"
#include "analysis/messages/verdict_proto.hpp"
#include "cli/cli_common.hpp"
#include "report/inspection_files.hpp"
#include "report/report_html.hpp"

namespace springscan::cli {
namespace {

constexpr const char* kName = "analyze";
using Clock = std::chrono::steady_clock;

double ms_since(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

// The text-format parser's first error, as "line:column: message" (1-based).
class FirstError : public google::protobuf::io::ErrorCollector {
 public:
  void AddError(int line, google::protobuf::io::ColumnNumber column,
                const std::string& message) override {
    if (message_.empty())
      message_ = std::to_string(line + 1) + ":" + std::to_string(column + 1) + ": " + message;
  }
  const std::string& message() const { return message_; }

 private:
  std::string message_;
};

analysis::Expected<v1::AnalysisSettings> read_settings(const std::string& path) {
  auto text = analysis::read_file_bytes(path);
  if (!text) return text.error();
  v1::AnalysisSettings settings;
  FirstError errors;
  google::protobuf::TextFormat::Parser parser;
  parser.RecordErrorsTo(&errors);
  if (!parser.ParseFromString(*text, &settings))
    return analysis::fail(analysis::ErrorCode::kInvalidSettings, path + ":" + errors.message());
  return settings;
}

// The CAD side: import, healing, even samples, segmentation into flanges and bends, and the
// exact surface distance (analysis/cad/model.hpp).
analysis::Expected<analysis::PartModel> load_cad_model(const std::string& path,
                                                       const v1::CadModelSettings& m) {
  auto settings = analysis::from_proto(m);
  if (!settings) return settings.error();
  return analysis::load_part_model(path, *settings);
}

analysis::Expected<analysis::PartModel> load_point_model(const std::string& path) {
  auto cloud = analysis::read_point_cloud(path);
  if (!cloud) return cloud.error();
  auto model = analysis::part_model_from_points(*cloud);
  if (!model) return model.error().prepend(path + ": ");
  auto sha256 = analysis::sha256_file(path);
  if (!sha256) return sha256.error();
  model->model.source_sha256 = std::move(*sha256);
  return std::move(model->model);
}

// The scan: its points, and with the mesh decimation on, the triangles too (a scanner's STL or
// a PLY with faces). Without it, PLY faces are skipped unparsed, as they always were.
struct LoadedScan {
  analysis::PointCloud cloud;
  std::vector<std::array<std::uint32_t, 3>> triangles;
};

analysis::Expected<LoadedScan> load_scan(const std::string& path, bool as_mesh) {
  if (!as_mesh) {
    auto cloud = analysis::read_point_cloud(path);
    if (!cloud) return cloud.error();
    return LoadedScan{std::move(*cloud), {}};
  }
  auto surface = analysis::read_surface(path);
  if (!surface) return surface.error();
  if (surface->triangles.empty())
    return analysis::fail(path +
                          ": reduction.mesh_decimation is on but the scan has no "
                          "triangles (decimation needs a mesh: STL, or PLY with faces)");
  return LoadedScan{std::move(surface->cloud), std::move(surface->triangles)};
}

// One line on what the decimation did, before the verdict.
void print_decimation(const analysis::MeshScanReduction& r) {
  if (!r.decimated) return;
  std::printf(
      "mesh decimation: %zu -> %zu vertices, %zu -> %zu triangles (%.1f%% removed), max "
      "deviation %.4f mm, %.0f ms\n",
      r.vertices_in, r.vertices_out, r.triangles_in, r.triangles_out,
      r.triangles_in ? 100.0 * (1.0 - static_cast<double>(r.triangles_out) / r.triangles_in) : 0.0,
      r.max_deviation_mm, r.time_ms);
}

// The verdict and the figures a quality engineer looks at first, on stdout.
void print_summary(const v1::InspectionReport& report, const std::string& out_dir,
                   bool compensation_files) {
  const v1::Verdict& verdict = report.verdict();
  const bool undecided = verdict.decision() == v1::Verdict::UNDECIDED;
  std::printf("verdict: %s (%s)\n",
              verdict.pass() ? "PASS"
              : undecided    ? "UNDECIDED: within the measurement uncertainty of a limit"
                             : "FAIL",
              verdict.decision_rule() == v1::VerdictSettings::SIMPLE ? "simple rule"
                                                                     : "guard band, ISO 14253-1");
  for (const auto& reason : report.verdict().reasons()) std::printf("  - %s\n", reason.c_str());
  std::printf(
      "global fit: residual rms %.4f mm to the surface after %d iterations; deviation p95 "
      "%.4f mm, %.1f%% beyond %.3g mm\n",
      report.global_fit().rms_residual(), report.global_fit().iterations(),
      report.deviation().p95(), 100.0 * report.deviation().fraction_out_of_tolerance(),
      report.deviation().tolerance_mm());
  for (const auto& bend : report.bends()) {
    if (!bend.measured()) {
      std::printf("bend %d: nominal %.2f deg, not measured\n", bend.id(), bend.nominal_angle_deg());
      continue;
    }
    std::printf("bend %d: nominal %.2f deg, measured %.2f deg, springback %+.3f deg (%s)\n",
                bend.id(), bend.nominal_angle_deg(), bend.measured_angle_deg(),
                bend.springback_deg(), bend.pass() ? "ok" : "out of tolerance");
  }
  std::printf("report: %s/report.html (also report.json, report.pb, deviation.ply%s); %.0f ms\n",
              out_dir.c_str(),
              compensation_files ? ", compensation.csv/.ply, compensated-surface.stl" : "",
              report.timings_ms().total());
}

}  // namespace

int analyze_main(int argc, char** argv) {
  ArgParser args(
      kName,
      "springscan analyze --cad PART.igs --scan SCAN.ply --out DIR [--model MODEL.ply] "
      "[--settings FILE.textproto] [--tolerance MM] [--angle-tolerance DEG] [--decimate]",
      "Fits the scan to the part (PCA + ICP), measures the signed deviation of every "
      "scan point and writes DIR/report.json, DIR/report.pb and DIR/deviation.ply. "
      "Exit 0 when the analysis ran (whatever the verdict), 1 when it failed, 2 on "
      "bad usage or unreadable input.");
  args.add_option("cad", "FILE", "the part: IGES or STEP (exact distances)");
  args.add_option("model", "FILE", "instead of --cad: model points (PLY, XYZ/CSV, STL)");
  args.add_option("scan", "FILE", "the scan: PLY, XYZ/CSV/TXT/PTS or STL, in mm");
  args.add_option("out", "DIR", "output directory (created)");
  args.add_option("settings", "FILE", "AnalysisSettings in protobuf text format");
  args.add_option("tolerance", "MM", "surface tolerance (deviation and verdict)");
  args.add_option("angle-tolerance", "DEG", "springback tolerance per bend (verdict)");
  args.add_option("serial", "S", "the individual part's serial (input.part_serial; msa type3)");
  args.add_switch("decimate",
                  "the scan is a mesh (STL, PLY with faces): reduce it by mesh decimation first "
                  "(reduction.mesh_decimation, docs/decimation.md)");
  Logger log;
  if (auto exit_code = args.start(argc, argv, log)) return *exit_code;
  for (const char* required : {"scan", "out"})
    if (!args.has(required))
      return fail_with(kName, std::string("--") + required + " is required", kExitUsage);
  if (args.has("cad") == args.has("model"))
    return fail_with(kName, "give exactly one of --cad PART.igs and --model MODEL.ply", kExitUsage);

  v1::AnalysisSettings settings;
  if (args.has("settings")) {
    auto loaded = read_settings(args.get("settings"));
    if (!loaded) return fail_with(kName, loaded.message(), kExitUsage);
    settings = std::move(*loaded);
  }
  for (const char* name : {"tolerance", "angle-tolerance"}) {
    if (!args.has(name)) continue;
    const auto value = args.get_number(name);
    if (!value)
      return fail_with(kName, std::string("--") + name + " " + args.get(name) + ": not a number",
                       kExitUsage);
    // The verdict owns both tolerances; its loader checks them (one range, verdict_proto.hpp).
    if (std::string(name) == "tolerance") {
      settings.mutable_verdict()->set_tolerance_mm(*value);
    } else {
      settings.mutable_verdict()->set_angle_tolerance_deg(*value);
    }
  }
  if (args.has("decimate"))
    settings.mutable_reduction()->mutable_mesh_decimation()->set_enabled(true);
  if (auto verdict = analysis::verdict_settings_from_proto(settings); !verdict)
    return fail_with(kName, verdict.message(), kExitUsage);

  auto start = Clock::now();
  const bool as_mesh = settings.reduction().mesh_decimation().enabled();
  auto scan = load_scan(args.get("scan"), as_mesh);
  if (!scan) return fail_with(kName, scan.message(), kExitUsage);
  const double load_ms = ms_since(start);
  start = Clock::now();
  auto model = args.has("cad") ? load_cad_model(args.get("cad"), settings.cad_model())
                               : load_point_model(args.get("model"));
  if (!model) return fail_with(kName, model.message(), kExitUsage);
  const double model_ms = ms_since(start);
  log.info("scan " + std::to_string(scan->cloud.size()) + " points" +
           (as_mesh ? ", " + std::to_string(scan->triangles.size()) + " triangles" : "") +
           ", model " + std::to_string(model->samples.size()) + " samples");

  auto outcome = as_mesh
                     ? analysis::run_mesh_inspection(*model, scan->cloud, scan->triangles, settings)
                     : analysis::run_inspection(*model, scan->cloud, settings);
  if (!outcome) return fail_with(kName, outcome.message(), kExitAnalysisFailed);
  v1::InspectionReport& report = outcome->report;
  report.mutable_input()->set_cad_file(args.get(args.has("cad") ? "cad" : "model"));
  report.mutable_input()->set_scan_file(args.get("scan"));
  report.mutable_input()->set_part_serial(args.get("serial"));
  auto& timings = *report.mutable_timings_ms();
  timings.set_load(load_ms);
  timings.set_model(model_ms);
  timings.set_total(timings.total() + load_ms + model_ms);
  report::stamp_report(report);
  for (const auto& warning : report.warnings()) log.warning(warning);

  std::error_code ec;
  std::filesystem::create_directories(args.get("out"), ec);
  if (ec) return fail_with(kName, args.get("out") + ": cannot create: " + ec.message(), kExitUsage);
  auto written = report::write_inspection_files(args.get("out"), *outcome);
  if (!written) return fail_with(kName, written.message(), kExitUsage);
  if (!written->html_error.empty()) log.warning("report.html not written: " + written->html_error);
  if (!args.has("quiet")) print_decimation(outcome->mesh_reduction);
  if (!args.has("quiet"))
    print_summary(report, args.get("out"), !outcome->compensation.vectors.empty());
  return kExitOk;
}

}  // namespace springscan::cli
