// springscan calibrate: each scanner head's transform into the station frame, fitted to the
// calibration artefact's CAD (analysis/registration/calibration.hpp, docs/calibration.md), written
// as the scanner section of springscand's config.
#include <google/protobuf/text_format.h>
#include <google/protobuf/util/json_util.h>

#include <cstdio>
#include <ctime>
#include <filesystem>
#include <string>

#include "analysis/cad/model.hpp"
#include "analysis/io/file_io.hpp"
#include "analysis/io/point_io.hpp"
#include "analysis/messages/calibration_proto.hpp"
#include "analysis/registration/calibration.hpp"
#include "cli/cli_common.hpp"
#include "drivers/scanner_proto.hpp"

namespace springscan::cli {
namespace {

constexpr const char* kName = "calibrate";

std::string utc_now() {
  const std::time_t now = std::time(nullptr);
  std::tm utc{};
  gmtime_r(&now, &utc);
  char text[32];
  std::strftime(text, sizeof text, "%Y-%m-%dT%H:%M:%SZ", &utc);
  return text;
}

void print_head(const analysis::HeadCalibration& h, const std::string& name, bool scale) {
  const analysis::Transform& T = h.T_station_head;
  std::printf("%s: %zu points (%zu fitted, %zu inliers), residual rms %.4f mm, p95 %.4f mm\n",
              name.c_str(), h.points, h.fitted_points, h.inliers, h.rms_mm, h.p95_mm);
  std::printf("  transform (head -> station, row-major):\n");
  for (int r = 0; r < 4; ++r)
    std::printf("    %12.8f %12.8f %12.8f %12.5f\n", T(r, 0), T(r, 1), T(r, 2), T(r, 3));
  if (scale) std::printf("  motion scale %.7f +- %.7f\n", h.motion_scale, h.motion_scale_sigma);
  std::printf(
      "  uncertainty (1 sigma, at %.1f %.1f %.1f): rotation %.5f %.5f %.5f deg, translation "
      "%.5f %.5f %.5f mm\n",
      h.centre.x(), h.centre.y(), h.centre.z(), h.rotation_sigma_deg.x(), h.rotation_sigma_deg.y(),
      h.rotation_sigma_deg.z(), h.translation_sigma_mm.x(), h.translation_sigma_mm.y(),
      h.translation_sigma_mm.z());
}

/// The scanner section springscand reads: the primary head's laser calibration and the record.
v1::DaemonConfig fragment(const v1::StationCalibration& record,
                          const analysis::HeadCalibration& primary) {
  v1::DaemonConfig config;
  v1::ScannerConfig* scanner = config.mutable_scanner();
  scanner->set_kind(v1::ScannerConfig::LASER_LINE);
  analysis::to_laser_calibration(primary, scanner->mutable_laser_calibration());
  *scanner->mutable_calibration() = record;
  return config;
}

std::string fragment_text(const v1::DaemonConfig& config, const v1::StationCalibration& record) {
  std::string text;
  google::protobuf::TextFormat::PrintToString(config, &text);
  return "# springscan calibrate, " + record.created_utc() + ", artefact " +
         record.artefact_file() + " (sha256 " + record.artefact_sha256() +
         ").\n# The scanner section of springscand's config (docs/calibration.md): "
         "laser_calibration "
         "is the\n# first head's; calibration records every head's fit.\n" +
         text;
}

analysis::Expected<std::string> json_of(const v1::StationCalibration& record) {
  google::protobuf::util::JsonPrintOptions options;
  options.add_whitespace = true;
  options.always_print_primitive_fields = true;
  options.preserve_proto_field_names = true;
  std::string json;
  const auto status = google::protobuf::util::MessageToJsonString(record, &json, options);
  if (!status.ok()) return analysis::fail("cannot print the calibration as JSON");
  return json;
}

int write_outputs(const ArgParser& args, const std::string& text, const std::string& json) {
  if (args.has("json")) {
    auto written = analysis::write_file_atomically(args.get("json"), json);
    if (!written) return fail_with(kName, written.message(), kExitUsage);
  }
  auto written = analysis::write_file_atomically(args.get("out"), text);
  if (!written) return fail_with(kName, written.message(), kExitUsage);
  return kExitOk;
}

}  // namespace

int calibrate_main(int argc, char** argv) {
  ArgParser args(
      kName,
      "--artefact ARTEFACT.step --scan HEAD_A.ply [--scan HEAD_B.ply ...] "
      "--out CALIBRATION.textproto [--json FILE] [--fit-motion-scale]",
      "Fits each head's rigid transform (head -> station) to the calibration artefact's\n"
      "CAD with the exact distance and the ICP, robust to outliers, and writes the\n"
      "scanner section of springscand's config. Each scan is one head's points of the\n"
      "artefact in the head's own frame: (x along the line, z range, encoder) for a\n"
      "line scanner. A view that leaves a direction free is refused, naming it, and\n"
      "nothing is written (exit 1).");
  args.add_option("artefact", "FILE", "the artefact's CAD (STEP or IGES)");
  args.add_option("scan", "FILE", "one head's scan (PLY, XYZ/CSV, STL); repeat for each head");
  args.add_option("out", "FILE", "the config fragment (protobuf text format)");
  args.add_option("json", "FILE", "also the fits as JSON (heads[].transform, ...)");
  args.add_switch("fit-motion-scale", "also fit the encoder scale (a line scanner's travel)");
  Logger log;
  if (auto done = args.start(argc, argv, log)) return *done;
  for (const char* required : {"artefact", "scan", "out"})
    if (!args.has(required))
      return fail_with(kName, std::string("--") + required + " is required", kExitUsage);
  auto artefact = analysis::load_part_model(args.get("artefact"));
  if (!artefact) return fail_with(kName, artefact.message(), kExitUsage);
  analysis::HeadCalibrationSettings settings;
  settings.fit_motion_scale = args.has("fit-motion-scale");
  v1::StationCalibration record;
  record.set_created_utc(utc_now());
  record.set_artefact_file(args.get("artefact"));
  record.set_artefact_sha256(artefact->source_sha256);
  analysis::HeadCalibration primary;
  for (const std::string& path : args.get_all("scan")) {
    const std::string name = std::filesystem::path(path).filename().string();
    auto scan = analysis::read_point_cloud(path);
    if (!scan) return fail_with(kName, scan.message(), kExitUsage);
    auto head = analysis::calibrate_head(scan->points, *artefact, settings);
    if (!head) return fail_with(kName, name + ": " + head.message(), kExitAnalysisFailed);
    if (!args.has("quiet")) print_head(*head, name, settings.fit_motion_scale);
    analysis::to_proto(*head, name, record.add_heads());
    if (record.heads_size() == 1) primary = *head;
  }
  const v1::DaemonConfig config = fragment(record, primary);
  // The check springscand --check makes of the scanner section, before anything is written.
  if (auto usable = drivers::check_scanner_config(config.scanner()); !usable)
    return fail_with(kName, "the calibration is not usable: " + usable.message(),
                     kExitAnalysisFailed);
  auto json = json_of(record);
  if (!json) return fail_with(kName, json.message(), kExitAnalysisFailed);
  return write_outputs(args, fragment_text(config, record), *json);
}

}  // namespace springscan::cli
