#!/usr/bin/env bash
# Fails when a tracked C++ file is not formatted by .clang-format (Debian's clang-format).
#   scripts/check-format.sh         check (CI)
#   scripts/check-format.sh --fix   format in place
# The files go to clang-format in batches, one batch per core at a time (45 s file by file).
set -euo pipefail
cd "$(dirname "$0")/.."
command -v clang-format >/dev/null || { echo "check-format: clang-format is not installed" >&2; exit 2; }
mapfile -t files < <(git ls-files '*.cpp' '*.hpp' '*.h')
batches=(xargs -0 -P "$(nproc)" -n 25)
if [[ "${1:-}" == --fix ]]; then
  printf '%s\0' "${files[@]}" | "${batches[@]}" clang-format -i
  exit 0
fi
# --dry-run --Werror names each file it would change ("FILE:LINE:COL: error: code should be
# clang-formatted"); the list of those files is the verdict.
mapfile -t bad < <(printf '%s\0' "${files[@]}" |
  "${batches[@]}" clang-format --dry-run --Werror 2>&1 >/dev/null |
  sed -n 's/^\([^:]*\):[0-9]*:[0-9]*: error: .*clang-format.*/\1/p' | sort -u || true)
if ((${#bad[@]} > 0)); then
  printf 'check-format: not clang-format clean (run scripts/check-format.sh --fix):\n' >&2
  printf '  %s\n' "${bad[@]}" >&2
  exit 1
fi
echo "check-format: ${#files[@]} files clean"
