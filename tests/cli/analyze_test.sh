#!/usr/bin/env bash
# springscan analyze end to end on the bundled demo pair (demo/README.md): the springback of
# every bend against the demo's constructed truth (1.5, 0.8, 1.1 and 0.4 degrees, bends 0 to 3;
# docs/springback.md claims 0.05 degree at sigma 0.02 mm), every file of docs/report-format.md
# written, the report stamped with the version and time, --quiet quiet, a broken scan
# refused with exit 2 and the file's name, and --decimate on a mesh scan and on a point scan.
#   analyze_test.sh SPRINGSCAN_BINARY DEMO_DIR
set -euo pipefail
bin=$1
demo=$2
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
check() { if ! eval "$1"; then echo "FAILED: $1" >&2; exit 1; fi; }

"$bin" analyze --cad "$demo/hat-profile.step" --scan "$demo/hat-profile-scan.ply" \
  --out "$tmp/out" >"$tmp/stdout"
check 'grep -q "^verdict: " "$tmp/stdout"'
for f in report.json report.pb report.html deviation.ply compensation.csv compensation.ply \
  compensated-surface.stl; do
  check "test -s '$tmp/out/$f'"
done
python3 - "$tmp/out/report.json" <<'PY'
import json, re, sys
report = json.load(open(sys.argv[1]))
truth = {0: 1.5, 1: 0.8, 2: 1.1, 3: 0.4}
bends = {b["id"]: b for b in report["bends"]}
assert sorted(bends) == sorted(truth), f"bends {sorted(bends)}"
for i, expected in truth.items():
    got = bends[i]["springback_deg"]
    assert abs(got - expected) <= 0.05, f"bend {i}: springback {got:.3f}, truth {expected}"
assert re.fullmatch(r"\d+\.\d+\.\d+", report["software_version"]), report["software_version"]
assert re.fullmatch(r"\d{4}-\d\d-\d\dT\d\d:\d\d:\d\dZ", report["created_utc"]), report["created_utc"]
PY

# --quiet: nothing on stdout, the files all the same; --serial lands in input.part_serial (the
# type-3 gauge study groups by it, issue 42).
"$bin" analyze --cad "$demo/hat-profile.step" --scan "$demo/hat-profile-scan.ply" \
  --out "$tmp/quiet" --quiet --serial "HAT-0042" >"$tmp/quiet.stdout"
check 'test ! -s "$tmp/quiet.stdout"'
check 'test -s "$tmp/quiet/report.json"'
check 'grep -q "\"part_serial\": \"HAT-0042\"" "$tmp/quiet/report.json"'

# A PLY cut short: exit 2, one line naming the file, nothing written.
head -c 3000 "$demo/hat-profile-scan.ply" >"$tmp/cut.ply"
status=0
"$bin" analyze --cad "$demo/hat-profile.step" --scan "$tmp/cut.ply" --out "$tmp/cut" \
  2>"$tmp/cut.stderr" >/dev/null || status=$?
check '[[ $status -eq 2 ]]'
check 'grep -q "cut.ply" "$tmp/cut.stderr"'
check 'test ! -e "$tmp/cut/report.json"'
# --decimate: a mesh scan (here the compensated CAD tessellation the first run wrote, an STL)
# is reduced by mesh decimation and analysed; a point scan is refused with exit 2.
"$bin" analyze --cad "$demo/hat-profile.step" --scan "$tmp/out/compensated-surface.stl" \
  --decimate --out "$tmp/mesh" >"$tmp/mesh.stdout" 2>"$tmp/mesh.stderr"
check 'grep -q "^mesh decimation: [0-9]* -> [0-9]* vertices" "$tmp/mesh.stdout"'
check 'grep -q "^verdict: " "$tmp/mesh.stdout"'
check 'test -s "$tmp/mesh/report.json"'
status=0
"$bin" analyze --cad "$demo/hat-profile.step" --scan "$demo/hat-profile-scan.ply" --decimate \
  --out "$tmp/points" 2>"$tmp/points.stderr" >/dev/null || status=$?
check '[[ $status -eq 2 ]]'
check 'grep -q "has no triangles" "$tmp/points.stderr"'
echo "analyze: OK"
