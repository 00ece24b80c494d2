#!/usr/bin/env bash
# springscan model end to end: the datum candidates of the openamr front panel against its STEP
# file's geometry (a 2 mm sheet whose largest flange, the panel, lies at z = 0 with its outward
# normal +z; two 22.5 mm holes through it at x = -130 and 130, y = 90.5), and the text form.
#   model_test.sh SPRINGSCAN_BINARY SHARED_DIR
set -euo pipefail
bin=$1
part=$2/data/cad/openamr-MMP.00.00.00.001_Front_panel.step
"$bin" model --json "$part" | python3 -c '
import json, sys
c = json.load(sys.stdin)["datum_candidates"]
pad = c["pads"][0]
assert abs(pad["point"][2]) < 1e-6 and abs(pad["normal"][2] - 1) < 1e-9, pad
assert abs(pad["thickness_mm"] - 2) < 1e-6, pad
assert all(a["area_mm2"] >= b["area_mm2"] for a, b in zip(c["pads"], c["pads"][1:]))
big = [h for h in c["holes"] if abs(h["diameter_mm"] - 22.5) < 1e-6]
assert sorted(round(h["centre"][0], 6) for h in big) == [-130, 130], big
for h in big:
    assert abs(h["centre"][1] - 90.5) < 1e-6 and abs(h["centre"][2]) < 1e-6, h
    assert abs(h["axis"][2] - 1) < 1e-9 and h["flange"] == pad["flange"], h
assert all(a["diameter_mm"] >= b["diameter_mm"] for a, b in zip(c["holes"], c["holes"][1:]))
'
text=$("$bin" model "$part")
# 14: the four 4.3 mm openings in the walls are 4.3 x 8 mm slots (docs/alignment.md)
grep -q "datum candidates: round holes (14)" <<<"$text"
echo "model: ok"
