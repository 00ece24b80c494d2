// springscan convert IN OUT [--ascii] [--single-precision]: any point or mesh format we read to
// any we write, chosen by the file extensions (analysis/io/point_io.hpp).
#include "analysis/io/point_io.hpp"
#include "cli/cli_common.hpp"

namespace springscan::cli {

int convert_main(int argc, char** argv) {
  ArgParser args("convert", "IN OUT [--ascii] [--single-precision]",
                 "Converts a scan or mesh between PLY, XYZ/CSV/TXT/PTS and STL, by extension.\n"
                 "Normals, colours, scalars and triangles are kept where OUT's format has room:\n"
                 "XYZ keeps x y z, normals and the scalar; STL keeps only triangles (binary).\n"
                 "Exit codes: 0 converted, 1 OUT could not be written, 2 bad usage or\n"
                 "unreadable IN.");
  args.add_switch("ascii", "write PLY as ascii instead of binary little endian");
  args.add_switch("single-precision", "write PLY coordinates as float instead of double");
  switch (args.parse(argc, argv, 2)) {
    case ArgParser::Outcome::kHelpShown:
      return kExitOk;
    case ArgParser::Outcome::kUsageError:
      return fail_with("convert", args.error(), kExitUsage);
    case ArgParser::Outcome::kRun:
      break;
  }
  Logger log;
  if (!args.configure_logger(log)) return fail_with("convert", args.error(), kExitUsage);
  if (args.positionals().size() != 2) {
    return fail_with("convert", "expects IN and OUT (see springscan convert --help)", kExitUsage);
  }
  const std::string& in = args.positionals()[0];
  const std::string& out = args.positionals()[1];
  const auto out_format = analysis::point_format_for_path(out);
  if (!out_format) {
    return fail_with("convert", out + ": unknown output extension (.ply .xyz .csv .txt .pts .stl)",
                     kExitUsage);
  }
  if (args.has("ascii") && *out_format != analysis::PointFormat::kPly) {
    return fail_with("convert", "--ascii applies to PLY output only (XYZ is text, STL binary)",
                     kExitUsage);
  }

  auto surface = analysis::read_surface(in);
  if (!surface) return fail_with("convert", surface.message(), kExitUsage);
  if (*out_format == analysis::PointFormat::kStl && surface->triangles.empty()) {
    return fail_with("convert", in + " has no triangles; STL output needs a mesh", kExitUsage);
  }

  analysis::PointWriteOptions options;
  if (args.has("ascii")) options.ply_encoding = analysis::PlyEncoding::kAscii;
  options.single_precision = args.has("single-precision");
  if (auto written = analysis::write_surface(out, *surface, options); !written) {
    return fail_with("convert", written.message(), kExitAnalysisFailed);
  }
  log.info("wrote " + std::to_string(surface->cloud.size()) + " points and " +
           std::to_string(surface->triangles.size()) + " triangles to " + out);
  return kExitOk;
}

}  // namespace springscan::cli
