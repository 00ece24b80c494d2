// springscan scan: one acquisition from the configured scanner (docs/device-protocol.md),
// written as a point file in part coordinates.
#include <google/protobuf/text_format.h>

#include <cmath>
#include <fstream>
#include <sstream>
#include <string>

#include "analysis/io/point_io.hpp"
#include "cli/cli_common.hpp"
#include "drivers/scanner_proto.hpp"

namespace springscan::cli {
namespace {

constexpr const char* kName = "scan";

analysis::Expected<v1::ScannerConfig> load_config(const std::string& path) {
  std::ifstream in(path);
  if (!in) return analysis::fail(path + ": cannot open");
  std::stringstream text;
  text << in.rdbuf();
  v1::DaemonConfig config;
  if (!google::protobuf::TextFormat::ParseFromString(text.str(), &config))
    return analysis::fail(path + ": not a DaemonConfig in protobuf text format");
  return config.scanner();
}

// Flags override the config file: --kind, --vid, --pid, --serial, --timeout.
std::string apply_flags(ArgParser& args, v1::ScannerConfig& c) {
  if (args.has("kind")) {
    const std::string kind = args.get("kind");
    if (kind == "laser") {
      c.set_kind(v1::ScannerConfig::LASER_LINE);
    } else if (kind == "tactile") {
      c.set_kind(v1::ScannerConfig::TACTILE_PROBE);
    } else {
      return "--kind " + kind + ": expected laser or tactile";
    }
  }
  if (args.has("genicam")) {
    // `--genicam [ID]`: a GenICam profiler through Aravis; the id is the one positional.
    v1::GenicamConfig* g = c.mutable_genicam();
    if (args.positionals().size() > 1) return "--genicam takes at most one camera id";
    if (!args.positionals().empty()) g->set_camera_id(args.positionals().front());
    if (args.has("line-step")) {
      const auto step = args.get_number("line-step");
      if (!step) return args.error();
      g->set_line_step_mm(*step);
    }
    if (args.has("lines")) {
      const auto lines = args.get_number("lines");
      if (!lines) return args.error();
      g->set_scan_lines(static_cast<std::int32_t>(*lines));
    }
  }
  if (c.kind() == v1::ScannerConfig::KIND_UNSPECIFIED) c.set_kind(v1::ScannerConfig::LASER_LINE);
  for (const char* name : {"vid", "pid"}) {
    if (!args.has(name)) continue;
    const std::string text = args.get(name);
    char* end = nullptr;
    const unsigned long value = std::strtoul(text.c_str(), &end, 16);
    if (text.empty() || *end != '\0' || value == 0 || value > 0xFFFF)
      return std::string("--") + name + " " + text + ": expected a hexadecimal id 1..ffff";
    if (std::string(name) == "vid") {
      c.set_vendor_id(static_cast<std::uint32_t>(value));
    } else {
      c.set_product_id(static_cast<std::uint32_t>(value));
    }
  }
  if (args.has("serial")) c.set_serial(args.get("serial"));
  if (args.has("timeout")) {
    const auto t = args.get_number("timeout");
    if (!t) return args.error();
    c.set_timeout_s(*t);
  }
  return "";
}

}  // namespace

int scan_main(int argc, char** argv) {
  ArgParser args(kName, "springscan scan --out scan.ply [options] [--genicam [ID]]",
                 "Runs one scan on the configured scanner (USB or GenICam, "
                 "docs/device-protocol.md) and "
                 "writes the points in part coordinates. Flags override the config file.");
  args.add_option("out", "FILE", "the scan (.ply, .xyz/.csv/.txt)");
  args.add_option("config", "FILE", "daemon config (protobuf text format); its scanner section");
  args.add_option("kind", "KIND", "laser (default) or tactile");
  args.add_option("vid", "HEX", "USB vendor id (default 1209)");
  args.add_option("pid", "HEX", "USB product id (default 5301 laser, 5302 tactile)");
  args.add_option("serial", "TEXT", "USB serial number; default: the first match");
  args.add_option("timeout", "S", "longest silence between data frames (default 2)");
  args.add_switch("genicam",
                  "a GenICam 3D line profiler through Aravis (GigE Vision, USB3 Vision); an id "
                  "after it (Aravis id or IP address) picks the camera, else the first found");
  args.add_option("line-step", "MM", "--genicam: travel per line (encoder-triggered lines)");
  args.add_option("lines", "N", "--genicam: lines the scan acquires (default 500)");
  Logger log;
  if (auto exit_code = args.start(argc, argv, log)) return *exit_code;
  if (!args.has("out")) return fail_with(kName, "--out is required", kExitUsage);
  v1::ScannerConfig config;
  if (args.has("config")) {
    auto loaded = load_config(args.get("config"));
    if (!loaded) return fail_with(kName, loaded.message(), kExitUsage);
    config = *loaded;
  }
  if (const std::string bad = apply_flags(args, config); !bad.empty())
    return fail_with(kName, bad, kExitUsage);
  auto scanner = drivers::make_scanner(config);
  if (!scanner) return fail_with(kName, scanner.message(), kExitUsage);
  auto info = (*scanner)->identify();
  if (!info) return fail_with(kName, info.message(), kExitAnalysisFailed);
  log.info("scanner " + info->model + " serial " + info->serial + " firmware " + info->firmware +
           " (" + info->kind + ")");
  auto cloud = (*scanner)->scan([&log](double done) {
    log.progress("scanning " + std::to_string(static_cast<int>(std::lround(done * 100))) + " %");
    return true;
  });
  log.end_progress();
  if (!cloud) return fail_with(kName, cloud.message(), kExitAnalysisFailed);
  if (auto written = analysis::write_point_cloud(args.get("out"), *cloud); !written)
    return fail_with(kName, written.message(), kExitUsage);
  log.info(std::to_string(cloud->size()) + " points written to " + args.get("out"));
  return kExitOk;
}

}  // namespace springscan::cli
