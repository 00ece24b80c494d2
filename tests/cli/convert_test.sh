#!/usr/bin/env bash
# springscan convert end to end: conversions between every format, exit codes, one-line errors.
#   convert_test.sh SPRINGSCAN_BINARY TEST_DATA_DIR
set -euo pipefail
bin=$1
data=$2
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
check() { if ! eval "$1"; then echo "FAILED: $1" >&2; exit 1; fi; }

# PLY (binary, normals, colours) -> XYZ -> ascii PLY: 10 points survive, with normals.
"$bin" convert "$data/open3d_cloud_binary.ply" "$tmp/cloud.xyz" --quiet
check '[[ $(grep -vc "^#" "$tmp/cloud.xyz") == 10 ]]'
check '[[ $(head -2 "$tmp/cloud.xyz" | tail -1) == "0 0 -0 1 0 0" ]]'
"$bin" convert "$tmp/cloud.xyz" "$tmp/cloud.PLY" --ascii --quiet
check 'grep -q "^format ascii 1.0$" "$tmp/cloud.PLY"'
check 'grep -q "^element vertex 10$" "$tmp/cloud.PLY"'
check 'grep -q "^property double nx$" "$tmp/cloud.PLY"'
check 'grep -q "^9 18 -4.5 " "$tmp/cloud.PLY"'

# STL (binary) -> PLY keeps the 12 triangles on 8 unique vertices -> STL again.
"$bin" convert "$data/open3d_cube_binary.stl" "$tmp/cube.ply" --ascii --quiet
check 'grep -q "^element vertex 8$" "$tmp/cube.ply"'
check 'grep -q "^element face 12$" "$tmp/cube.ply"'
"$bin" convert "$tmp/cube.ply" "$tmp/cube.stl" --quiet
check '[[ $(stat -c %s "$tmp/cube.stl") == 684 ]]'  # 84 + 12 * 50 bytes
"$bin" convert "$data/cube_ascii.stl" "$tmp/cube.csv" --quiet
check '[[ $(grep -vc "^#" "$tmp/cube.csv") == 8 ]]'
check '[[ -z $(ls -A "$tmp" | grep "\.tmp$" || true) ]]'

# Failures: exit 2 with one line on stderr naming the problem.
set +e
"$bin" convert "$tmp/missing.ply" "$tmp/x.ply" 2>"$tmp/err"; code=$?
check '[[ $code == 2 && $(wc -l <"$tmp/err") == 1 ]] && grep -q "missing.ply" "$tmp/err"'
"$bin" convert "$tmp/cloud.xyz" "$tmp/x.stl" 2>"$tmp/err"; code=$?
check '[[ $code == 2 ]] && grep -q "no triangles" "$tmp/err"'
"$bin" convert "$tmp/cloud.xyz" 2>"$tmp/err"; code=$?
check '[[ $code == 2 ]] && grep -q "expects IN and OUT" "$tmp/err"'
"$bin" convert "$tmp/cloud.xyz" "$tmp/x.obj" 2>"$tmp/err"; code=$?
check '[[ $code == 2 ]] && grep -q "unknown output extension" "$tmp/err"'
printf 'ply\nformat ascii 1.0\nelement vertex 99\nproperty float x\nend_header\n' >"$tmp/bad.ply"
"$bin" convert "$tmp/bad.ply" "$tmp/x.xyz" 2>"$tmp/err"; code=$?
check '[[ $code == 2 ]] && grep -q "bad.ply" "$tmp/err"'
set -e
echo "convert_test: ok"
