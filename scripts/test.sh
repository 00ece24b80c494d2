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
  # build.sh tsan builds only the analysis and daemon test executables: their CTest labels.
  # Under TSan the accuracy sweeps (every orientation, profile, part and pose) are left out: they
  # run the same parallel stages as the pipeline, boundary and production tests kept here, 5-15x
  # slower, and were half of CI's TSan stage. The release suite runs them all.
  tsan) dir="$root/build-tsan"
        sweeps='^(GlobalFit\.|Orientation\.|Profiles/SpringbackAccuracy\.|Parts/FieldAccuracy\.'
        sweeps+='|BendShape\.|Springback\.Repeated|Profiles/BoundaryFit\.|Openamr/DatumPart\.'
        sweeps+='|Openamr/ProductionPart\.(ZeroSpringback|PointsOnly))'
        select=(-L '^(analysis|daemon)$' -E "$sweeps") ;;
  *) dir="$root/build" ;;
esac
export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1:abort_on_error=1}
export LSAN_OPTIONS=${LSAN_OPTIONS:-suppressions=$root/tests/sanitizer/lsan.supp}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}
export TSAN_OPTIONS=${TSAN_OPTIONS:-halt_on_error=1:second_deadlock_stack=1:suppressions=$root/tests/sanitizer/tsan.supp}
ctest --test-dir "$dir" --output-on-failure --parallel "$(nproc)" --timeout 600 "${select[@]}"
