#!/usr/bin/env bash
# The station's own gauge capability studies on the simulator (docs/calibration.md, "The
# station's own studies"): the demo station (scripts/station-lib.sh: springscand, the simulated
# dual-head laser scanner over emulated USB, the simulated PLC) measures the demo bracket
#   type 1: one part (springback 1.5, 0.8, 1.1, 0.4 deg at bends 0-3) in 50 PLC cycles, the
#           part re-placed each time (up to 2 mm and 1 deg) with fresh noise; the reference is
#           the springback built in;
#   type 3: 10 parts (their springback 0.3 deg apart from first to last, 0.033 deg per part)
#           x 3 trials, each trial re-placed, the PLC writing each part's PART_SERIAL;
# then `springscan msa type1` and `type3` over the report stores, and prints Cg, Cgk, %GRR and
# ndc per bend.
#   scripts/station-msa.sh [OUT_DIR]     default out/station-msa; about 3 minutes on 2 cores
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
out=${1:-$root/out/station-msa}
SPRINGSCAN_WITH_EXTRAS=0 "$root/scripts/install-deps.sh"
"$root/scripts/build.sh" release springscan-demo-part springscan-scanner-sim springscand \
  springscan-plc-sim springscan >/dev/null
bin="$root/build"
cad="$root/demo/motor-bracket.step"
rm -rf "$out" && mkdir -p "$out/type1" "$out/type3"
source "$root/scripts/station-lib.sh"
# Each scan finds the part placed anew; no pacing of the scan (the studies are about the numbers).
placement=(--duration 0 --replace-mm 2 --replace-deg 1)

springback=(1.5 0.8 1.1 0.4)
joined() { local IFS=,; echo "$*"; }
"$bin/simulators/springscan-demo-part" --production "$cad" --springback "$(joined "${springback[@]}")" \
  --surface "$out/type1/produced-surface.ply" >/dev/null
echo "== type 1: 50 cycles of one part"
station_run "$bin" "$out/type1" "$cad" "$out/type1/produced-surface.ply" 50 \
  "${placement[@]}" --seed 11 -- --serial 1 >"$out/type1/plc.log"
python3 - "$out/type1/produced-surface-truth.json" "$out/type1/reference.json" <<'PY'
import json, sys
truth = json.load(open(sys.argv[1]))["bends"]
json.dump({"bend %d springback" % b["id"]: b["springback_deg"] for b in truth}, open(sys.argv[2], "w"))
PY
"$bin/cli/springscan" msa type1 "$out/type1/reports" --reference "$out/type1/reference.json" \
  --out "$out/msa-type1.html" --json "$out/msa-type1.json"

echo "== type 3: 10 parts x 3 trials"
for part in $(seq 1 10); do
  part_springback=()
  for s in "${springback[@]}"; do
    part_springback+=("$(python3 -c "print(round($s + ($part - 5.5) * 0.3 / 9, 4))")")
  done
  "$bin/simulators/springscan-demo-part" --production "$cad" \
    --springback "$(joined "${part_springback[@]}")" --surface "$out/type3/part-$part.ply" >/dev/null
  station_run "$bin" "$out/type3" "$cad" "$out/type3/part-$part.ply" 3 \
    "${placement[@]}" --seed "$((100 + part))" -- --serial "$part" --job-start "$((10 * part))" \
    >>"$out/type3/plc.log"
done
# The bends' springback, what the station decides parts by (the page of all characteristics,
# deviations included: `springscan msa type3 "$out/type3/reports" --out FILE`).
bends=()
for k in "${!springback[@]}"; do bends+=(--characteristic "bend $k springback"); done
"$bin/cli/springscan" msa type3 "$out/type3/reports" "${bends[@]}" --out "$out/msa-type3.html" \
  --json "$out/msa-type3.json"

python3 - "$out/msa-type1.json" "$out/msa-type3.json" <<'PY'
import json, sys
t1 = {c["name"]: c for c in json.load(open(sys.argv[1]))["characteristics"]}
t3 = {c["name"]: c for c in json.load(open(sys.argv[2]))["characteristics"]}
print("| characteristic | T | type 1: s | bias | Cg | Cgk | type 3: EV | PV | %GRR of T | ndc |")
print("| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |")
for name in sorted(t1):
    a, b = t1[name], t3.get(name, {})
    print("| %s | %.2f | %.4f | %+.4f | %.1f | %.1f | %.4f | %.4f | %.2f %% | %.1f |" % (
        name, a.get("tolerance", float("nan")), a["stddev"], a["bias"], a.get("cg", float("nan")),
        a.get("cgk", float("nan")), b.get("ev", float("nan")), b.get("pv", float("nan")),
        b.get("grr_pct_tolerance", float("nan")), b.get("ndc", float("nan"))))
PY
echo "== pages: $out/msa-type1.html, $out/msa-type3.html"
