#!/usr/bin/env bash
# Runs every springscan test: installs what is missing, builds (Release, incremental), runs CTest.
#   scripts/test.sh             the Release build
#   scripts/test.sh sanitize    the same suite under ASan + UBSan
#   scripts/test.sh tsan        the analysis and daemon tests (HIL included) under ThreadSanitizer,
#                               without the accuracy sweeps
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
kind=${1:-release}
"$root/scripts/install-deps.sh"
"$root/scripts/build.sh" "$kind"
select=()
case "$kind" in
  sanitize) dir="$root/build-asan" ;;
  # build.sh tsan builds only the analysis and daemon test executables, and of the analysis
  # tests only those of the stages that run threads (tests/analysis/CMakeLists.txt). Of these,
  # the accuracy sweeps (every pose, profile and part) are left out too: they run the same
  # parallel stages as the pipeline, boundary and production tests kept here, 5-15x slower
  # under TSan. The release and ASan suites run them all.
  tsan) dir="$root/build-tsan"
        sweeps='^(Profiles/BoundaryFit\.|Openamr/DatumPart\.'
        sweeps+='|Openamr/ProductionPart\.(ZeroSpringback|PointsOnly))'
        select=(-L '^(analysis|daemon)$' -E "$sweeps") ;;
  *) dir="$root/build" ;;
esac
# CTest starts the tests it knows to be long first, from the cost data of the tree's earlier
# runs. A fresh clone has none, so it starts from the costs committed in tests/ctest-costs/
# (copied from a run's Testing/Temporary/CTestCostData.txt): a long test no longer starts last
# and runs alone on one core at the end.
costs="$dir/Testing/Temporary/CTestCostData.txt"
if [[ ! -f "$costs" && -f "$root/tests/ctest-costs/$kind.txt" ]]; then
  mkdir -p "$(dirname "$costs")"
  cp "$root/tests/ctest-costs/$kind.txt" "$costs"
fi
export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1:abort_on_error=1}
export LSAN_OPTIONS=${LSAN_OPTIONS:-suppressions=$root/tests/sanitizer/lsan.supp}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}
export TSAN_OPTIONS=${TSAN_OPTIONS:-halt_on_error=1:second_deadlock_stack=1:suppressions=$root/tests/sanitizer/tsan.supp}
# Twice as many tests at once as there are cores, but no more computing tests than cores: each
# takes one of the spec's "cpu" slots (tests/CMakeLists.txt, SPRINGSCAN_COMPUTING_TEST), and the
# daemon and hardware-in-the-loop tests, which mostly wait, run in the gaps.
# (At least two slots: the fault campaign takes two, bench/CMakeLists.txt.)
cores=$(nproc)
slots=$((cores > 2 ? cores : 2))
spec="$dir/Testing/resources.json"
mkdir -p "$(dirname "$spec")"
printf '{"version": {"major": 1, "minor": 0}, "local": [{"cpu": [{"id": "0", "slots": %d}]}]}\n' \
  "$slots" >"$spec"
ctest --test-dir "$dir" --output-on-failure --parallel "$((2 * cores))" --resource-spec-file "$spec" \
  --timeout 600 "${select[@]}"
