#!/usr/bin/env bash
# Where CI's time went: for each build tree that exists, the ten slowest compile units (ninja's
# log of the last build, so a ccache hit counts as the time the hit took) and the ten slowest
# tests (CTest's cost data: the mean over the runs it has seen). .ci/run prints this at its end,
# so a unit or a test that got slower shows the day it lands.
#   scripts/ci-times.sh [BUILD_DIR...]     default: build-asan build-tsan build
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
dirs=("$@")
# The first ten lines, reading the rest: `head` would exit early and, under pipefail, the SIGPIPE
# that stops `sort` would fail the whole CI run after every stage had passed (exit 141).
top_ten() { awk 'NR <= 10'; }
((${#dirs[@]} > 0)) || dirs=("$root/build-asan" "$root/build-tsan" "$root/build")
for dir in "${dirs[@]}"; do
  [[ -d "$dir" ]] || continue
  echo "== $(basename "$dir"): ten slowest compile units (s)"
  if [[ -f "$dir/.ninja_log" ]]; then
    # .ninja_log v5: start_ms end_ms mtime output hash; the last entry of an output is its newest.
    awk -F'\t' 'NR > 1 && $4 ~ /\.o$/ { t[$4] = ($2 - $1) / 1000 }
                END { for (o in t) printf "%8.1f  %s\n", t[o], o }' "$dir/.ninja_log" |
      sort -rn | top_ten
  elif [[ -f "$dir/compile-times.log" ]]; then
    sort -rn "$dir/compile-times.log" | top_ten
  else
    echo "   (no ninja log: a Makefile tree)"
  fi
  cost="$dir/Testing/Temporary/CTestCostData.txt"
  if [[ -f "$cost" ]]; then
    echo "== $(basename "$dir"): ten slowest tests (s)"
    # Lines "name runs mean_seconds" until the "---" that starts the failed list.
    awk '/^---/ { exit } NF == 3 && $2 > 0 { printf "%8.1f  %s\n", $3, $1 }' "$cost" |
      sort -rn | top_ten
  fi
done
