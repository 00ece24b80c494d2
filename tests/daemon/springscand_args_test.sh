#!/usr/bin/env bash
# springscand's command line: --help and --version answer on stdout with exit 0; a bad
# argument gets one error line, the usage (ending in a newline) and exit 2.
# --check loads every part's CAD file and validates its settings: 0 when usable, 2 otherwise.
#   springscand_args_test.sh SPRINGSCAND_BINARY SOURCE_ROOT
set -uo pipefail
bin=$1
src=$2
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
config() {  # config(cad_file, settings)
  cat >"$tmp/c.textproto" <<CONFIG
modbus { bind_address: "127.0.0.1" port: 0 }
scanner { kind: LASER_LINE }
parts { part_id: 1 name: "demo" cad_file: "$1" $2 }
report_dir: "$tmp/reports"
model_cache_dir: "$tmp/cache"
CONFIG
}
config "$src/demo/hat-profile.step" ""
"$bin" --check --config "$tmp/c.textproto" >"$tmp/out" 2>&1; rc=$?
[[ $rc == 0 ]] || fail "--check of a good config: exit $rc: $(cat "$tmp/out")"
grep -q "part 1 (demo): .*hat-profile.step loads: .* 4 bends" "$tmp/out" || fail "--check did not load the CAD: $(cat "$tmp/out")"
grep -q "calibration in force: the scanner's default mount, no record of springscan calibrate" "$tmp/out" || fail "--check did not name the calibration: $(cat "$tmp/out")"
grep -q "no check part" "$tmp/out" || fail "--check did not say there is no check part: $(cat "$tmp/out")"

# The calibration in force (the record springscan calibrate writes, docs/calibration.md) and
# the check part, as --check names them.
config "$src/demo/hat-profile.step" ""
sed -i 's|^scanner { kind: LASER_LINE }|scanner { kind: LASER_LINE calibration { created_utc: "2026-12-06T21:30:00Z" artefact_file: "/etc/springscan/artefact.step" heads { name: "head_a.ply" } heads { name: "head_b.ply" } } }|' "$tmp/c.textproto"
echo 'check_part { part_id: 1 reference { characteristic: "bend 1 springback" value: 0.4 limit: 0.05 } }' >>"$tmp/c.textproto"
"$bin" --check --config "$tmp/c.textproto" >"$tmp/out" 2>&1; rc=$?
[[ $rc == 0 ]] || fail "--check with a calibration record and a check part: exit $rc: $(cat "$tmp/out")"
grep -q "calibration in force: made 2026-12-06T21:30:00Z by springscan calibrate from artefact /etc/springscan/artefact.step, 2 head(s): head_a.ply, head_b.ply" "$tmp/out" || fail "--check did not name the calibration record: $(cat "$tmp/out")"
grep -q "check part: part 1, 1 reference(s)" "$tmp/out" || fail "--check did not name the check part: $(cat "$tmp/out")"

config "$src/demo/hat-profile.step" "settings { registration { max_iterations: -3 } }"
"$bin" --check --config "$tmp/c.textproto" >"$tmp/out" 2>&1; rc=$?
[[ $rc == 2 ]] || fail "--check of bad part settings: exit $rc"
grep -q "c.textproto:3:.*max_iterations" "$tmp/out" || fail "bad settings not named with file:line: $(cat "$tmp/out")"

printf 'ISO-10303-21;\nHEADER;\nnot a step file\n' >"$tmp/broken.step"
config "$tmp/broken.step" ""
"$bin" --check --config "$tmp/c.textproto" >"$tmp/out" 2>&1; rc=$?
[[ $rc == 2 ]] || fail "--check of a broken CAD file: exit $rc"
grep -q "part 1 (demo): .*broken.step" "$tmp/out" || fail "broken CAD not named: $(cat "$tmp/out")"

# The operator page's section (docs/operator-page.md): off without it, its address with it, a
# bad field named with file:line.
config "$src/demo/hat-profile.step" ""
"$bin" --check --config "$tmp/c.textproto" >"$tmp/out" 2>&1
grep -q "operator page off" "$tmp/out" || fail "--check did not say the page is off: $(cat "$tmp/out")"
echo 'http { port: 8081 }' >>"$tmp/c.textproto"
"$bin" --check --config "$tmp/c.textproto" >"$tmp/out" 2>&1; rc=$?
[[ $rc == 0 ]] || fail "--check with http { }: exit $rc: $(cat "$tmp/out")"
grep -q "operator page on http://127.0.0.1:8081/" "$tmp/out" || fail "--check did not give the page's address: $(cat "$tmp/out")"
config "$src/demo/hat-profile.step" ""
echo 'http { address: "localhost" }' >>"$tmp/c.textproto"
"$bin" --check --config "$tmp/c.textproto" >"$tmp/out" 2>&1; rc=$?
[[ $rc == 2 ]] || fail "--check of a bad http address: exit $rc"
grep -q "c.textproto:6:.*http.address: 'localhost' is not an IPv4 address" "$tmp/out" || fail "bad http address not named: $(cat "$tmp/out")"
echo "springscand arguments: 12 checks passed"
