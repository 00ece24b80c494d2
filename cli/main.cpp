// springscan: the command-line front of the inspection station (DESIGN.md). This program runs
// the light commands itself and execs springscan-commands for the rest (cli/commands.hpp says
// why: a command pays at start-up for every shared library its program links).
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <iostream>
#include <string>

#include "cli/cli_common.hpp"
#include "cli/commands.hpp"

namespace springscan::cli {
namespace {

const Command kCommands[] = {
    {"version", "print the version", version_main},
    {"analyze", "fit a scan to its part and measure the deviation (report files)", nullptr},
    {"match", "pair model and scan points by exact min-cost matching", match_main},
    {"model", "show a CAD file's faces, flanges and bends (text or JSON)", nullptr},
    {"report", "render the HTML report again from a saved report.pb", nullptr},
    {"scan", "acquire one scan from the configured USB scanner", nullptr},
    {"convert", "convert a scan or mesh between PLY, XYZ/CSV and STL", nullptr},
    {"trend", "control charts, Cp/Cpk and run rules over many reports (HTML)", nullptr},
    {"msa", "gauge capability studies, type 1 (Cg, Cgk) and type 3 (%GRR, ndc)", nullptr},
    {"calibrate", "fit each scanner head's transform to the calibration artefact", nullptr},
    {"compensate", "the compensated die surface as STEP, from a report's deformation field",
     nullptr},
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

// springscan-commands beside this program's own file (/proc/self/exe: the real file, whatever
// path or symlink it was started by), so the build tree and an install both work.
std::string commands_program() {
  char self[4096];
  const ssize_t n = readlink("/proc/self/exe", self, sizeof self - 1);
  if (n <= 0) return kCommandsProgram;
  std::string path(self, static_cast<std::size_t>(n));
  path.resize(path.rfind('/') + 1);
  return path + kCommandsProgram;
}

// Replaces this process with springscan-commands, same argv; returns only when that fails.
int run_in_commands_program(const char* command, char** argv) {
  const std::string program = commands_program();
  execv(program.c_str(), argv);
  const int error = errno;
  return fail_with(command,
                   "cannot run " + program + ": " + std::strerror(error) +
                       " (springscan is not installed completely)",
                   kExitAnalysisFailed);
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
    if (std::strcmp(argv[1], command.name) != 0) continue;
    return command.run != nullptr ? command.run(argc, argv)
                                  : run_in_commands_program(command.name, argv);
  }
  std::cerr << "springscan: unknown command '" << argv[1] << "' (springscan --help lists them)\n";
  return kExitUsage;
}
