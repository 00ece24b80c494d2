#!/usr/bin/env bash
# The station demo: springscand with the simulated laser scanner (an emulated USB device, so
# the production libusb driver runs) and the simulated PLC (a Modbus TCP client on loopback).
# The PLC triggers one inspection of a production part, the bundled motor bracket (demo/README.md:
# a 2 mm hat bracket with four 90 degree bends, as produced with a known springback per bend);
# the daemon scans it, analyses against demo/motor-bracket.step, stores the report and answers
# on the register map. Prints the verdict, every bend beside its truth, and where the report is.
# Installs and builds what is missing first.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
# Only what the demo runs: the build packages (not the test peers: Chromium, mosquitto, scipy),
# and the four programs (not the test suites and benches), so a newcomer's first command is a
# few minutes on a fresh machine; `bash scripts/test.sh` adds the rest.
SPRINGSCAN_WITH_EXTRAS=0 "$root/scripts/install-deps.sh"
"$root/scripts/build.sh" release springscan-demo-part springscan-scanner-sim springscand \
  springscan-plc-sim >/dev/null
bin="$root/build"
out="$root/out/demo"
rm -rf "$out" && mkdir -p "$out"

# The bracket as produced (springback 1.5, 0.8, 1.1, 0.4 deg at bends 0 to 3), the surface the
# simulated scanner measures, and its truth (produced-surface-truth.json).
"$bin/simulators/springscan-demo-part" --production "$root/demo/motor-bracket.step" \
  --springback 1.5,0.8,1.1,0.4 --surface "$out/produced-surface.ply" >/dev/null

# The station: springscand under the simulated scanner, and the simulated PLC triggering one
# inspection of part 1 (scripts/station-lib.sh).
source "$root/scripts/station-lib.sh"
echo "== PLC: trigger one inspection of part 1"
station_run "$bin" "$out" "$root/demo/motor-bracket.step" "$out/produced-surface.ply" 1

report=$(ls -d "$out"/reports/r* | tail -n 1)
echo "== station log: $out/station.log"
echo "== report: $report/report.html (report.json, report.pb, deviation.ply beside it)"
python3 - "$report/report.json" "$out/produced-surface-truth.json" <<'PY'
import json, sys
r = json.load(open(sys.argv[1]))
truth = {b["id"]: b["springback_deg"] for b in json.load(open(sys.argv[2]))["bends"]}
v = r["verdict"]
print("verdict:", "PASS" if v.get("pass") else "FAIL")
for reason in v.get("reasons", []):
    print("  -", reason)
for b in r.get("bends", []):
    i = b.get("id", 0)
    if not b.get("measured"):
        print("bend %d: nominal %.2f deg, not measured (the report's warnings say why)" % (
            i, b.get("nominal_angle_deg", 0)))
        continue
    print("bend %d: nominal %.2f deg, measured %.2f deg, springback %+.3f deg (built in: %.3f)" % (
        i, b.get("nominal_angle_deg", 0), b.get("measured_angle_deg", 0),
        b.get("springback_deg", 0), truth.get(i, float("nan"))))
PY
