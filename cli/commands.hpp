#pragma once
// The subcommands of `springscan`. Each lives in cli/cmd_<name>.cpp and is listed in main.cpp.

namespace springscan::cli {

/// Each subcommand's entry point: argv[0] is "springscan", argv[1] the command's name.
using CommandMain = int (*)(int argc, char** argv);

struct Command {
  const char* name;
  const char* summary;
  CommandMain run;
};

}  // namespace springscan::cli
