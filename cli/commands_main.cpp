// springscan-commands: the springscan commands that need OpenCASCADE, VTK, the scanner drivers
// or protobuf. Users run them as `springscan COMMAND`, which execs this program with the same
// argv (cli/commands.hpp); argv[1] is the command's name, as in springscan.
#include <cstring>
#include <iostream>

#include "cli/cli_common.hpp"
#include "cli/commands.hpp"

namespace springscan::cli {
namespace {

struct HeavyCommand {
  const char* name;
  CommandMain run;
};

// The commands main.cpp lists without an entry point of its own.
const HeavyCommand kCommands[] = {
    {"analyze", analyze_main}, {"model", model_main},         {"report", report_main},
    {"scan", scan_main},       {"convert", convert_main},     {"trend", trend_main},
    {"msa", msa_main},         {"calibrate", calibrate_main}, {"compensate", compensate_main},
};

}  // namespace
}  // namespace springscan::cli

int main(int argc, char** argv) {
  using namespace springscan::cli;
  if (argc >= 2) {
    for (const auto& command : kCommands) {
      if (std::strcmp(argv[1], command.name) == 0) return command.run(argc, argv);
    }
  }
  std::cerr << "springscan-commands: run it as springscan COMMAND (springscan --help lists them)\n";
  return kExitUsage;
}
