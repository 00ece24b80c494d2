// springscan: the command-line front of the inspection station (DESIGN.md).
#include <cstring>
#include <iostream>
#include <string>

#include "cli/cli_common.hpp"
#include "cli/commands.hpp"

namespace springscan::cli {

// One line per subcommand; the implementations live in cmd_<name>.cpp.
int version_main(int argc, char** argv);
int match_main(int argc, char** argv);
int report_main(int argc, char** argv);
int scan_main(int argc, char** argv);
int convert_main(int argc, char** argv);
int analyze_main(int argc, char** argv);
int model_main(int argc, char** argv);
int trend_main(int argc, char** argv);
int msa_main(int argc, char** argv);
int calibrate_main(int argc, char** argv);
int compensate_main(int argc, char** argv);

namespace {

const Command kCommands[] = {
    {"version", "print the version", version_main},
    {"analyze", "fit a scan to its part and measure the deviation (report files)", analyze_main},
    {"match", "pair model and scan points by exact min-cost matching", match_main},
    {"model", "show a CAD file's faces, flanges and bends (text or JSON)", model_main},
    {"report", "render the HTML report again from a saved report.pb", report_main},
    {"scan", "acquire one scan from the configured USB scanner", scan_main},
    {"convert", "convert a scan or mesh between PLY, XYZ/CSV and STL", convert_main},
    {"trend", "control charts, Cp/Cpk and run rules over many reports (HTML)", trend_main},
    {"msa", "gauge capability studies, type 1 (Cg, Cgk) and type 3 (%GRR, ndc)", msa_main},
    {"calibrate", "fit each scanner head's transform to the calibration artefact", calibrate_main},
    {"compensate", "the compensated die surface as STEP, from a report's deformation field",
     compensate_main},
};

void print_usage() {
  std::cout << "usage: springscan COMMAND [options]   (springscan COMMAND --help for details)\n\n"
               "commands:\n";
  for (const auto& command : kCommands) {
    std::string name = command.name;
    name.resize(12, ' ');
    std::cout << "  " << name << command.summary << '\n';
  }
}

}  // namespace

int version_main(int, char**) {
  std::cout << "springscan " << SPRINGSCAN_VERSION << '\n';
  return kExitOk;
}

}  // namespace springscan::cli

int main(int argc, char** argv) {
  using namespace springscan::cli;
  if (argc < 2 || std::strcmp(argv[1], "--help") == 0 || std::strcmp(argv[1], "help") == 0) {
    print_usage();
    return argc < 2 ? kExitUsage : kExitOk;
  }
  if (std::strcmp(argv[1], "--version") == 0) return version_main(argc, argv);
  for (const auto& command : kCommands) {
    if (std::strcmp(argv[1], command.name) == 0) return command.run(argc, argv);
  }
  std::cerr << "springscan: unknown command '" << argv[1] << "' (springscan --help lists them)\n";
  return kExitUsage;
}
