#pragma once
// The subcommands of `springscan`. Each lives in cli/cmd_<name>.cpp and is listed in main.cpp.
//
// Two programs (docs/architecture.md "The command line"): `springscan`, the one users run, is
// linked only against what its in-process commands need (point files, k-center, the matching),
// so `springscan match` loads no OpenCASCADE, VTK, Aravis, libusb or protobuf; every other
// command runs in `springscan-commands`, which `springscan` execs with the same argv from
// ../lib/springscan/ relative to its own file (the same layout in the build tree and installed).

namespace springscan::cli {

/// Each subcommand's entry point: argv[0] is "springscan", argv[1] the command's name.
using CommandMain = int (*)(int argc, char** argv);

struct Command {
  const char* name;
  const char* summary;
  CommandMain run;  ///< in `springscan` itself; nullptr: the command is in springscan-commands
};

/// Where `springscan` finds springscan-commands, relative to the directory of its own file.
inline constexpr const char* kCommandsProgram = "../lib/springscan/springscan-commands";

// In `springscan` (light: no CAD, mesh, device or protobuf library).
int version_main(int argc, char** argv);
int match_main(int argc, char** argv);
// In `springscan-commands`.
int analyze_main(int argc, char** argv);
int model_main(int argc, char** argv);
int report_main(int argc, char** argv);
int scan_main(int argc, char** argv);
int convert_main(int argc, char** argv);
int trend_main(int argc, char** argv);
int msa_main(int argc, char** argv);
int calibrate_main(int argc, char** argv);
int compensate_main(int argc, char** argv);

}  // namespace springscan::cli
