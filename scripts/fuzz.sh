#!/usr/bin/env bash
# Runs a libFuzzer target of tests/fuzz for a while. The targets are built in the ASan + UBSan
# build (clang, build-asan/, scripts/build.sh sanitize), the tree the sanitizer suite uses.
#   scripts/fuzz.sh TARGET SECONDS     TARGET: point_files device_frames modbus_request
#                                              daemon_config report_pb, or all
# The corpus grows in build-asan/fuzz/corpus/TARGET (seeded from tests/fuzz/corpus/TARGET); a
# crash is written to build-asan/fuzz/findings/TARGET/ and the script exits non-zero. To keep a
# finding as a test, copy the input into tests/fuzz/corpus/TARGET/ (the replay test runs it ever
# after).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
targets=(point_files device_frames modbus_request daemon_config report_pb)
target=${1:?usage: scripts/fuzz.sh TARGET SECONDS}
seconds=${2:?usage: scripts/fuzz.sh TARGET SECONDS}
[[ "$target" == all ]] || targets=("$target")
"$root/scripts/install-deps.sh"
"$root/scripts/build.sh" sanitize "${targets[@]/#/fuzz_}"
build="$root/build-asan"
dir="$build/fuzz"
export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1:abort_on_error=1}
export LSAN_OPTIONS=${LSAN_OPTIONS:-suppressions=$root/tests/sanitizer/lsan.supp}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}
# One target: its corpus grows in corpus/TARGET, a crash lands in findings/TARGET, the summary
# lines go to logs/TARGET.log.
run_one() {
  local t=$1 corpus="$dir/corpus/$1" findings="$dir/findings/$1"
  mkdir -p "$corpus" "$findings" "$dir/logs"
  cp -n "$root/tests/fuzz/corpus/$t/"* "$corpus/" 2>/dev/null || true
  # rss_limit: hostile sizes must never make a parser allocate past what its bytes can hold.
  "$build/tests/fuzz/fuzz_$t" "$corpus" -max_total_time="$seconds" -rss_limit_mb=2048 \
    -timeout=10 -max_len=65536 -print_final_stats=1 -artifact_prefix="$findings/" 2>&1 |
    grep -E '^(#[0-9]+.*(DONE|pulse)|stat::|==[0-9]+==|SUMMARY|Done|INFO: seed)' \
      >"$dir/logs/$t.log" || true
}
# The targets are single-threaded: as many run at once as there are cores, so the stage takes
# seconds x targets / cores.
jobs_at_once=$(nproc)
failed=0
for ((i = 0; i < ${#targets[@]}; i += jobs_at_once)); do
  batch=("${targets[@]:i:jobs_at_once}")
  echo "== fuzz ${batch[*]} for $seconds s"
  for t in "${batch[@]}"; do run_one "$t" & done
  wait
  for t in "${batch[@]}"; do
    sed "s/^/[$t] /" "$dir/logs/$t.log"
    if compgen -G "$dir/findings/$t/*" >/dev/null; then
      echo "fuzz $t: findings in $dir/findings/$t" >&2
      failed=1
    fi
  done
done
exit "$failed"
