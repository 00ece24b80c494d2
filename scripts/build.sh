#!/usr/bin/env bash
# Configures (once) and builds springscan incrementally.
#   scripts/build.sh            Release build in build/
#   scripts/build.sh sanitize   AddressSanitizer + UndefinedBehaviorSanitizer build in build-asan/
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
kind=${1:-release}
case "$kind" in
  release) dir="$root/build"; flags=(-DCMAKE_BUILD_TYPE=Release) ;;
  sanitize) dir="$root/build-asan"
            flags=(-DCMAKE_BUILD_TYPE=RelWithDebInfo -DSPRINGSCAN_SANITIZE=ON
                   -DSPRINGSCAN_BUILD_BENCHMARKS=OFF) ;;
  *) echo "usage: scripts/build.sh [release|sanitize]" >&2; exit 2 ;;
esac
# CI gates warnings on the Release build. Not on the sanitizer build: g++ 12 reports false
# -Wmaybe-uninitialized inside libstdc++ (std::regex, std::function) under -fsanitize=address.
if [[ "${CI:-}" == true && "$kind" == release ]]; then flags+=(-DSPRINGSCAN_WERROR=ON); fi
launcher=()
if command -v ccache >/dev/null; then launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache); fi
if [[ ! -f "$dir/CMakeCache.txt" ]]; then
  # The Release build (README's test command, CI) uses CMake's default generator, so the plain
  # `cmake -S . -B build && cmake --build build` a newcomer types is the build CI proves; the
  # other kinds use Ninja, which is faster to rebuild.
  generator=(-G Ninja)
  [[ "$kind" == release ]] && generator=()
  cmake -S "$root" -B "$dir" "${generator[@]}" "${flags[@]}" "${launcher[@]}" >/dev/null
fi
cmake --build "$dir" --parallel "$(nproc)"
