#!/usr/bin/env bash
# springscand's command line: --help and --version answer on stdout with exit 0; a bad
# argument gets one error line, the usage (ending in a newline) and exit 2.
#   springscand_args_test.sh SPRINGSCAND_BINARY
set -uo pipefail
bin=$1
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail() { echo "FAILED: $*" >&2; exit 1; }

"$bin" --help >"$tmp/out" 2>"$tmp/err"; rc=$?
[[ $rc == 0 ]] || fail "--help exit $rc"
grep -q '^usage: springscand --config FILE \[--check\]$' "$tmp/out" || fail "--help: no usage line"
[[ ! -s "$tmp/err" ]] || fail "--help wrote to stderr"

"$bin" --version >"$tmp/out" 2>&1; rc=$?
[[ $rc == 0 ]] || fail "--version exit $rc"
grep -qE '^springscand [0-9]+\.[0-9]+\.[0-9]+$' "$tmp/out" || fail "--version: $(cat "$tmp/out")"

"$bin" --bogus >"$tmp/out" 2>"$tmp/err"; rc=$?
[[ $rc == 2 ]] || fail "unknown argument exit $rc"
[[ $(head -1 "$tmp/err") == "springscand: unknown argument --bogus" ]] || fail "error line: $(head -1 "$tmp/err")"
grep -q '^usage: ' "$tmp/err" || fail "no usage after the error"
[[ $(tail -c 1 "$tmp/err" | od -An -c | tr -d ' ') == '\n' ]] || fail "usage does not end in a newline"

"$bin" >"$tmp/out" 2>"$tmp/err"; rc=$?
[[ $rc == 2 ]] || fail "no --config exit $rc"
grep -q -- '--config FILE is required' "$tmp/err" || fail "missing --config not explained"
echo "springscand arguments: 4 checks passed"
