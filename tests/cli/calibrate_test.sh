#!/usr/bin/env bash
# springscan calibrate end to end (docs/calibration.md): springscan-artefact writes the artefact
# and three demo heads' raw scans of it (mounted 0.5 degree and 2 mm off their drawing, encoder
# scale 1.002, noise sigma 0.02 mm, 1 % outliers); the fitted transforms and scales must match
# the truth it wrote within 0.01 degree, 0.01 mm over the artefact and 1e-4; the config fragment
# carries the first head's laser_calibration and, as the scanner section of the shipped config,
# passes springscand --check; a view of a plane is refused, naming the free directions, with
# nothing written.
#   calibrate_test.sh SPRINGSCAN_BINARY ARTEFACT_BINARY SPRINGSCAND_BINARY SOURCE_DIR
set -euo pipefail
bin=$1
artefact=$2
daemon=$3
source=$4
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
check() { if ! eval "$1"; then echo "FAILED: $1" >&2; exit 1; fi; }

"$artefact" --out "$tmp" --scans >/dev/null
"$bin" calibrate --artefact "$tmp/calibration-artefact.step" --scan "$tmp/head-a.ply" \
  --scan "$tmp/head-b.ply" --scan "$tmp/head-c.ply" --out "$tmp/calibration.textproto" \
  --json "$tmp/calibration.json" --fit-motion-scale >"$tmp/stdout"
check 'grep -q "^head-b.ply: .* residual rms" "$tmp/stdout"'
check 'grep -q "^scanner {" "$tmp/calibration.textproto"'
check 'grep -q "laser_calibration {" "$tmp/calibration.textproto"'
python3 - "$tmp/calibration.json" "$tmp/truth.txt" "$tmp/calibration.textproto" <<'PY'
import json, math, re, sys
fits = {h["name"]: h for h in json.load(open(sys.argv[1]))["heads"]}
assert sorted(fits) == ["head-a.ply", "head-b.ply", "head-c.ply"], sorted(fits)
def matrix(numbers):
    return [numbers[4 * r:4 * r + 4] for r in range(4)]
def apply(T, k, p):
    q = (p[0], p[1], k * p[2])
    return [sum(T[r][c] * q[c] for c in range(3)) + T[r][3] for r in range(3)]
for line in open(sys.argv[2]):
    words = line.split()
    name, k_true, T_true = words[1], float(words[3]), matrix([float(w) for w in words[5:21]])
    fit = fits["head-%s.ply" % name]
    T, k = matrix(fit["transform"]), fit["motion_scale"]
    # Rotation error: the angle of R_fit^T R_true.
    trace = sum(T[r][c] * T_true[r][c] for r in range(3) for c in range(3))
    angle = math.degrees(math.acos(max(-1.0, min(1.0, (trace - 1.0) / 2.0))))
    # Displacement error over the artefact as the head sees it: x, z range, encoder corners.
    worst = max(math.dist(apply(T, k, p), apply(T_true, k_true, p))
                for p in [(x, z, e) for x in (-80, 80) for z in (190, 260) for e in (-60, 60)])
    print("head %s: rotation %.5f deg, displacement %.5f mm, scale %+.2e" %
          (name, angle, worst, k - k_true))
    assert angle < 0.01, angle
    assert worst < 0.01, worst
    assert abs(k - k_true) < 1e-4, k
    assert 0.01 < fit["rms_mm"] < 0.021, fit["rms_mm"]
# The fragment's laser calibration is the first head's: origin = its translation.
text = open(sys.argv[3]).read()
origin = re.search(r"origin_mm \{\s*x: (\S+)\s*y: (\S+)\s*z: (\S+)", text)
T = matrix(fits["head-a.ply"]["transform"])
assert all(abs(float(origin.group(i + 1)) - T[i][3]) < 1e-9 for i in range(3)), origin.groups()
PY

# The fragment is the scanner section springscand reads: the shipped config with its scanner
# section replaced by it (and its paths moved into the test's folder) passes --check.
python3 - "$source/config/springscand.textproto" "$tmp/calibration.textproto" "$source/demo" \
  "$tmp" >"$tmp/station.textproto" <<'PY'
import sys
config, fragment, demo, tmp = sys.argv[1:5]
text = open(config).read()
start = text.index("\nscanner {")
depth, end = 0, None
for i in range(text.index("{", start), len(text)):
    depth += {"{": 1, "}": -1}.get(text[i], 0)
    if depth == 0:
        end = i + 1
        break
text = text[:start] + text[end:]
text = text.replace("/usr/share/springscan/demo", demo).replace("/var/", tmp + "/var/")
print(text + "\n" + open(fragment).read())
PY
"$daemon" --config "$tmp/station.textproto" --check 2>"$tmp/check.stderr" ||
  { cat "$tmp/check.stderr" >&2; exit 1; }

# A flat patch (the head sees a plane): refused, the free directions named, nothing written.
python3 - "$tmp/plane.xyz" <<'PY'
import sys
with open(sys.argv[1], "w") as out:
    for i in range(40):
        for j in range(30):
            out.write("%.3f %.3f %.3f\n" % (i * 1.0, 230.0, j * 1.0))
PY
status=0
"$bin" calibrate --artefact "$tmp/calibration-artefact.step" --scan "$tmp/plane.xyz" \
  --out "$tmp/plane.textproto" --json "$tmp/plane.json" 2>"$tmp/plane.stderr" >/dev/null ||
  status=$?
check '[[ $status -eq 1 ]]'
check 'grep -q "direction(s) free: .*translation along" "$tmp/plane.stderr"'
check 'test ! -e "$tmp/plane.textproto" && test ! -e "$tmp/plane.json"'
echo "calibrate_test: ok"
