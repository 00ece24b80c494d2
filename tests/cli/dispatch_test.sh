#!/usr/bin/env bash
# springscan as two programs (cli/commands.hpp): springscan links none of the heavy libraries;
# every command it lists answers --help from whichever program holds it; springscan-commands is
# found from springscan's own file (also through a symlink); exit codes and one-line errors pass
# through the exec; without springscan-commands the light commands still run and the others say
# why they cannot, in one line.
#   dispatch_test.sh SPRINGSCAN_BINARY
set -euo pipefail
bin=$1
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
check() { if ! eval "$1"; then echo "FAILED: $1" >&2; exit 1; fi; }

# 1. What springscan loads: no CAD, mesh, device, GLib or protobuf library.
readelf -d "$bin" | awk '/\(NEEDED\)/ { print $NF }' >"$tmp/needed"
check '[[ -s "$tmp/needed" ]]'
heavy='TK|vtk|aravis|usb|glib|gio|gobject|protobuf|modbus|systemd|tbb'
if grep -Ei "$heavy" "$tmp/needed"; then echo "FAILED: springscan links a heavy library" >&2; exit 1; fi
# ... while springscan-commands does (the test would pass vacuously with both programs light).
commands=$(dirname "$bin")/../lib/springscan/springscan-commands
check '[[ -x "$commands" ]]'
# (Into a file first: `grep -q` stops reading at its match, and readelf, writing on, would die
# of SIGPIPE and fail the pipeline under pipefail.)
readelf -d "$commands" >"$tmp/commands_dynamic"
check 'grep -Eq "NEEDED.*(libTKernel|libprotobuf)" "$tmp/commands_dynamic"'

# 2. Every listed command answers --help with its own usage line, exit 0.
"$bin" --help >"$tmp/help"
awk '/^commands:/ { on = 1; next } on && NF { print $1 }' "$tmp/help" >"$tmp/names"
check '[[ $(wc -l <"$tmp/names") -ge 10 ]]'
while read -r name; do
  [[ "$name" == version ]] && continue
  "$bin" "$name" --help >"$tmp/out" 2>"$tmp/err" || { echo "FAILED: $name --help exit $?" >&2; exit 1; }
  check 'head -n 1 "$tmp/out" | grep -q "^usage: springscan $name"'
done <"$tmp/names"
check '[[ $("$bin" version) == "springscan "* ]]'

# 3. Exit codes and one-line errors through the exec: a usage error of a heavy command.
status=0
"$bin" model >"$tmp/out" 2>"$tmp/err" || status=$?
check '[[ $status -eq 2 ]]'
check '[[ $(wc -l <"$tmp/err") -eq 1 ]] && grep -q "^springscan model: " "$tmp/err"'
status=0
"$bin" no-such-command 2>"$tmp/err" || status=$?
check '[[ $status -eq 2 ]] && grep -q "unknown command .no-such-command." "$tmp/err"'
status=0
"$commands" 2>"$tmp/err" || status=$?
check '[[ $status -eq 2 ]] && grep -q "springscan COMMAND" "$tmp/err"'

# 4. Through a symlink in another folder: springscan-commands is found from the real file.
mkdir "$tmp/link"
ln -s "$(realpath "$bin")" "$tmp/link/springscan"
"$tmp/link/springscan" convert --help >"$tmp/link_help"
check 'grep -q "^usage: springscan convert" "$tmp/link_help"'

# 5. A springscan without springscan-commands beside it: match runs, model says why it cannot.
mkdir -p "$tmp/alone/bin"
cp "$bin" "$tmp/alone/bin/springscan"
printf '0 0 0\n10 0 0\n' >"$tmp/model.xyz"
printf '10.5 0 0\n0.5 0 0\n' >"$tmp/scan.xyz"
"$tmp/alone/bin/springscan" match --model "$tmp/model.xyz" --scan "$tmp/scan.xyz" \
  --out "$tmp/pairs.csv" --quiet
check '[[ $(sed -n 2p "$tmp/pairs.csv") == 0,1,0.25 && $(sed -n 3p "$tmp/pairs.csv") == 1,0,0.25 ]]'
status=0
"$tmp/alone/bin/springscan" model --help >"$tmp/out" 2>"$tmp/err" || status=$?
check '[[ $status -eq 1 && ! -s "$tmp/out" ]]'
check '[[ $(wc -l <"$tmp/err") -eq 1 ]]'
check 'grep -q "^springscan model: cannot run .*/lib/springscan/springscan-commands: No such file" "$tmp/err"'
echo "dispatch_test: OK"
