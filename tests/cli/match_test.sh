#!/usr/bin/env bash
# springscan match end to end: pairs.csv against optima the test constructs or finds
# by brute force, the one-to-one property, |model| > |scan|, input formats, exit codes and
# one-line errors.
#   match_test.sh SPRINGSCAN_BINARY
set -euo pipefail
bin=$1
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
check() { if ! eval "$1"; then echo "FAILED: $1" >&2; exit 1; fi; }

# Checks pairs.csv against the two point files: the header; one line per pair, `lines` of
# them; indices in range; no model and no scan index twice; each squared distance equal to
# the one computed from the files (1e-9 relative). Prints the total of the squared distances.
check_pairs() {  # MODEL SCAN PAIRS LINES
  awk -F'[ ,]+' -v lines="$4" '
    function fail(msg) { print "pairs: " msg > "/dev/stderr"; bad = 1; exit 1 }
    BEGIN { nm = 0; ns = 0 }
    FILENAME == ARGV[1] { mx[nm] = $1; my[nm] = $2; mz[nm] = $3; ++nm; next }
    FILENAME == ARGV[2] { sx[ns] = $1; sy[ns] = $2; sz[ns] = $3; ++ns; next }
    FNR == 1 { if ($0 != "model_index,scan_index,squared_distance_mm2") fail("header " $0); next }
    {
      if (NF != 3) fail("line " FNR ": " NF " fields")
      i = $1; j = $2
      if (i !~ /^[0-9]+$/ || i >= nm) fail("line " FNR ": model index " i)
      if (j !~ /^[0-9]+$/ || j >= ns) fail("line " FNR ": scan index " j)
      if (seen_m[i]++) fail("model index " i " twice")
      if (seen_s[j]++) fail("scan index " j " twice")
      d = (mx[i] - sx[j]) ^ 2 + (my[i] - sy[j]) ^ 2 + (mz[i] - sz[j]) ^ 2
      if ((d - $3) ^ 2 > (1e-9 * (d > 1 ? d : 1)) ^ 2) fail("line " FNR ": " $3 " != " d)
      total += $3; ++pairs
    }
    END {
      if (bad) exit 1
      if (pairs != lines) { print "pairs: " pairs " lines, expected " lines > "/dev/stderr"; exit 1 }
      printf "%.17g\n", total
    }' "$1" "$2" "$3"
}

# |a - b| <= 1e-9 max(|b|, 1e-12).
same_cost() { awk -v a="$1" -v b="$2" 'BEGIN { e = (a > b ? a - b : b - a); s = (b > 0 ? b : -b);
                                              exit !(e <= 1e-9 * (s > 1e-12 ? s : 1e-12)) }'; }

# 1. A known optimum. 60 model points on a 10 mm grid; scan line k holds model point
# (7k + 3) mod 60 moved by e_i, |e_i| <= 0.81 mm. Any other pairing puts some model point
# with a scan point >= 10 - 0.81 mm away, which costs more than the identity's |e_i|^2
# (10 mm spacing > 2 max |e|), so the optimum is: model i <-> line k with (7k + 3) mod 60 = i,
# total sum |e_i|^2.
n=60
awk -v n=$n 'BEGIN { for (i = 0; i < n; ++i)
  printf "%d %d %d\n", 10 * (i % 5), 10 * (int(i / 5) % 4), 10 * int(i / 20) }' >"$tmp/grid.xyz"
awk -v n=$n -v sum="$tmp/expected" 'BEGIN { for (k = 0; k < n; ++k) { i = (7 * k + 3) % n
  ex = 0.5 * sin(i + 1); ey = 0.5 * cos(3 * i); ez = 0.4 * sin(2 * i + 0.5)
  printf "%.17g %.17g %.17g\n", 10 * (i % 5) + ex, 10 * (int(i / 5) % 4) + ey, 10 * int(i / 20) + ez
  expected += ex * ex + ey * ey + ez * ez }
  printf "%.17g\n", expected > sum }' >"$tmp/moved.xyz"
"$bin" match --model "$tmp/grid.xyz" --scan "$tmp/moved.xyz" --out "$tmp/pairs.csv" 2>"$tmp/log"
total=$(check_pairs "$tmp/grid.xyz" "$tmp/moved.xyz" "$tmp/pairs.csv" $n)
check 'same_cost "$total" "$(cat "$tmp/expected")"'
wrong=$(awk -F, -v n=$n 'NR > 1 && (7 * $2 + 3) % n != $1' "$tmp/pairs.csv")
check '[[ -z $wrong ]]'
check 'grep -q "60 pairs (min_cost_matching).*coverage 1.000.*optimality certified" "$tmp/log"'
# The same clouds as binary PLY give the same pairs.
"$bin" convert "$tmp/grid.xyz" "$tmp/grid.ply" --quiet
"$bin" convert "$tmp/moved.xyz" "$tmp/moved.ply" --quiet
"$bin" match --model "$tmp/grid.ply" --scan "$tmp/moved.ply" --out "$tmp/pairs_ply.csv" --quiet
check 'cmp -s "$tmp/pairs.csv" "$tmp/pairs_ply.csv"'

# 2. Brute force: 6 model and 8 scan points scattered in a 10 mm cube (no obvious pairing);
# the cheapest of all 8!/2! injections.
lcg_points() {  # COUNT SEED
  awk -v n="$1" -v seed="$2" 'BEGIN { x = seed; for (i = 0; i < 3 * n; ++i) {
    x = (x * 16807) % 2147483647; printf "%.6f%s", 10 * x / 2147483647,
    (i % 3 == 2 ? "\n" : " ") } }'
}
brute_force() {  # ROWS COLS: the cheapest injection of ROWS' points into COLS' points
  awk '
    function search(depth, cost,   j) {
      if (cost >= best) return
      if (depth == m) { best = cost; return }
      for (j = 0; j < s; ++j) if (!used[j]) {
        used[j] = 1; search(depth + 1, cost + c[depth, j]); used[j] = 0 }
    }
    BEGIN { m = 0; s = 0 }
    FILENAME == ARGV[1] { px[m] = $1; py[m] = $2; pz[m] = $3; ++m; next }
    { qx[s] = $1; qy[s] = $2; qz[s] = $3; ++s }
    END {
      for (i = 0; i < m; ++i) for (j = 0; j < s; ++j)
        c[i, j] = (px[i] - qx[j]) ^ 2 + (py[i] - qy[j]) ^ 2 + (pz[i] - qz[j]) ^ 2
      best = 1e300; search(0, 0); printf "%.17g\n", best
    }' "$1" "$2"
}
lcg_points 6 11 >"$tmp/six.xyz"
lcg_points 8 23 >"$tmp/eight.xyz"
optimum=$(brute_force "$tmp/six.xyz" "$tmp/eight.xyz")
"$bin" match --model "$tmp/six.xyz" --scan "$tmp/eight.xyz" --out "$tmp/small.csv" --quiet
total=$(check_pairs "$tmp/six.xyz" "$tmp/eight.xyz" "$tmp/small.csv" 6)
check 'same_cost "$total" "$optimum"'

# 3. |model| > |scan| (documented in docs/matching.md): solved transposed; every scan point is
# used exactly once, 2 of the 8 model points stay without a partner, coverage 6/8.
"$bin" match --model "$tmp/eight.xyz" --scan "$tmp/six.xyz" --out "$tmp/more.csv" 2>"$tmp/log"
total=$(check_pairs "$tmp/eight.xyz" "$tmp/six.xyz" "$tmp/more.csv" 6)
check 'same_cost "$total" "$optimum"'
check 'grep -q "6 pairs (min_cost_matching), model 8, scan 6 points.*coverage 0.750" "$tmp/log"'

# 4. Failures: exit 2 (unreadable input, usage) with one line on stderr naming the problem,
# and no pairs file left behind.
set +e
run() { "$bin" match "$@" --out "$tmp/none.csv" 2>"$tmp/err"; code=$?; }
run --model "$tmp/missing.xyz" --scan "$tmp/six.xyz"
check '[[ $code == 2 && $(wc -l <"$tmp/err") == 1 ]] && grep -q "missing.xyz" "$tmp/err"'
printf '1 2 3\n4 5\n' >"$tmp/short.xyz"
run --model "$tmp/six.xyz" --scan "$tmp/short.xyz"
check '[[ $code == 2 && $(wc -l <"$tmp/err") == 1 ]] && grep -q "short.xyz: line 2" "$tmp/err"'
printf '1 2 3\nnan 5 6\n' >"$tmp/nan.xyz"
run --model "$tmp/nan.xyz" --scan "$tmp/six.xyz"
check '[[ $code == 2 ]] && grep -q "nan.xyz: line 2.*non-finite" "$tmp/err"'
printf 'ply\nformat ascii 1.0\nelement vertex 99\nproperty float x\nend_header\n' >"$tmp/bad.ply"
run --model "$tmp/six.xyz" --scan "$tmp/bad.ply"
check '[[ $code == 2 && $(wc -l <"$tmp/err") == 1 ]] && grep -q "bad.ply" "$tmp/err"'
: >"$tmp/empty.xyz"
run --model "$tmp/empty.xyz" --scan "$tmp/six.xyz"
check '[[ $code == 2 ]] && grep -q "empty.xyz: empty file" "$tmp/err"'
run --model "$tmp/six.xyz" --scan "$tmp/eight.xyz" --method closest
check '[[ $code == 2 ]] && grep -q "expected matching or nearest" "$tmp/err"'
"$bin" match --model "$tmp/six.xyz" --scan "$tmp/eight.xyz" 2>"$tmp/err"; code=$?
check '[[ $code == 2 ]] && grep -q -- "--out is required" "$tmp/err"'
check '[[ ! -e "$tmp/none.csv" ]]'
set -e
echo "match_test: ok"
