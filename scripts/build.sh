#!/usr/bin/env bash
# Configures (once) and builds springscan incrementally.
#   scripts/build.sh            Release build in build/
#   scripts/build.sh sanitize   AddressSanitizer + UndefinedBehaviorSanitizer build in build-asan/
#                               (clang), the libFuzzer targets of tests/fuzz included
#   scripts/build.sh tsan       ThreadSanitizer build in build-tsan/: only the analysis and daemon
#                               test executables (and springscand, which the HIL tests run)
#   scripts/build.sh KIND TARGET...  only those targets of that build
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
kind=${1:-release}
shift || true
targets=()
compilers=()
# The sanitizer builds at -O1 with line tables only: on the 2-core CI the ASan + UBSan build of
# the Eigen-heavy stages is most of the run (datum.cpp alone 100 s at -O2, 83 s at -O1), and
# line tables are all a sanitizer's stack trace needs. No -ffast-math and no FMA contraction
# (-std=c++20), so the numbers the tests check are the same at either level.
sanitizer_opt=("-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O1 -g1 -DNDEBUG")
case "$kind" in
  release) dir="$root/build"; flags=(-DCMAKE_BUILD_TYPE=Release) ;;
  # clang, so that the libFuzzer targets build in the same tree as the tests: one ASan + UBSan
  # compile of the project serves the suite and the fuzz stage (CI time, docs/performance.md).
  sanitize) dir="$root/build-asan"
            compilers=(CC=clang CXX=clang++)
            flags=(-DCMAKE_BUILD_TYPE=RelWithDebInfo "${sanitizer_opt[@]}" -DSPRINGSCAN_SANITIZE=ON
                   -DSPRINGSCAN_FUZZ=ON -DSPRINGSCAN_BUILD_BENCHMARKS=OFF) ;;
  # These reach every thread we start: the parallel analysis stages, and springscand's runner,
  # station and report figures (the report store renders report.html), and the USB emulator's
  # threads (HIL tests). The CLI, driver and report tests run no thread these do not, and would
  # only add build time on the 2-core CI.
  tsan) dir="$root/build-tsan"
        flags=(-DCMAKE_BUILD_TYPE=RelWithDebInfo "${sanitizer_opt[@]}" -DSPRINGSCAN_TSAN=ON
               -DSPRINGSCAN_BUILD_BENCHMARKS=OFF)
        targets=(--target springscan_analysis_tests springscan_daemon_tests springscan_hil_tests) ;;
  *) echo "usage: scripts/build.sh [release|sanitize|tsan] [TARGET...]" >&2; exit 2 ;;
esac
(($# > 0)) && targets=(--target "$@")
# A build-asan/ configured before the sanitizer build moved to clang is configured anew.
if [[ "$kind" == sanitize && -f "$dir/CMakeCache.txt" ]] &&
   ! grep -q '^SPRINGSCAN_FUZZ:BOOL=ON' "$dir/CMakeCache.txt"; then
  echo "build.sh: $dir was configured with g++; configuring it anew with clang" >&2
  rm -rf "$dir"
fi
# CI gates warnings on the Release build (g++), the one README's commands build. Not on the
# sanitizer builds: g++ 12 reports false -Wmaybe-uninitialized inside libstdc++ (std::regex,
# std::function) under -fsanitize=thread, and clang's warning set differs from g++'s.
if [[ "${CI:-}" == true && "$kind" == release ]]; then flags+=(-DSPRINGSCAN_WERROR=ON); fi
# ccache, with hits across checkouts (scripts/ccache-launcher.sh says how).
mapfile -t launcher < <(bash "$root/scripts/ccache-launcher.sh")
# A tree configured before the launcher carried base_dir is configured again (same options).
if [[ -f "$dir/CMakeCache.txt" && ${#launcher[@]} -gt 0 ]] &&
   ! grep -qF "${launcher[0]#*=}" "$dir/CMakeCache.txt"; then
  cmake "$dir" "${launcher[@]}" >/dev/null
fi
if [[ ! -f "$dir/CMakeCache.txt" ]]; then
  # The Release build (README's test command, CI) uses CMake's default generator, so the plain
  # `cmake -S . -B build && cmake --build build` a newcomer types is the build CI proves; the
  # other kinds use Ninja, which is faster to rebuild.
  generator=(-G Ninja)
  [[ "$kind" == release ]] && generator=()
  env "${compilers[@]}" cmake -S "$root" -B "$dir" "${generator[@]}" "${flags[@]}" "${launcher[@]}" \
    >/dev/null
fi
cmake --build "$dir" --parallel "$(nproc)" "${targets[@]}"
