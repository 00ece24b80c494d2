#!/usr/bin/env bash
# Prints the CMake argument that compiles through ccache (nothing without ccache), for
# scripts/build.sh and scripts/package.sh alike:
#   launcher=($(bash scripts/ccache-launcher.sh))
# ccache hits across checkouts: CI builds a fresh clone in another folder each time. base_dir
# makes ccache rewrite every absolute path under the checkout into one relative to the build
# directory (the same in every clone), and nohashdir leaves the build directory itself out of the
# hash (it is only in the debug info's DW_AT_comp_dir of the sanitizer builds' -g1 line tables).
# No test or program compiles an absolute path of the checkout into its sources: the tests take
# theirs from one generated file each (cmake/TestPaths.cmake). The settings are in the launcher,
# so a plain `cmake --build` of a configured tree hashes the same way. 8 GB holds the three build
# kinds (Release, ASan + UBSan, TSan) of two trees.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
command -v ccache >/dev/null || exit 0
echo "-DCMAKE_CXX_COMPILER_LAUNCHER=env;CCACHE_BASEDIR=$root;CCACHE_NOHASHDIR=true;CCACHE_MAXSIZE=8G;ccache"
