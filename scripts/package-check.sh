#!/usr/bin/env bash
# Installs the station's .deb on this machine, checks it as a plant would, removes it again:
#   1. dpkg -i (the postinst creates the springscan user and group);
#   2. springscand --check on the installed default config (it names the shipped demo part);
#   3. springscan as a user runs it: an in-process command (match, on two small point files) and
#      one springscan execs from /usr/lib/springscan (model --help), with their exit codes;
#   4. systemd-analyze verify on the installed unit;
#   5. dpkg --purge, and nothing of the package is left in /usr/bin, /usr/lib, /etc or /lib.
#   scripts/package-check.sh [DEB]    default: builds it with scripts/package.sh
# Needs root (dpkg). Exits non-zero at the first failing step.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
deb=${1:-$("$root/scripts/package.sh" | tail -n 1)}
sudo_cmd=()
if [[ $(id -u) -ne 0 ]]; then sudo_cmd=(sudo); fi
config=/etc/springscan/springscand.textproto
unit=/lib/systemd/system/springscand.service
if dpkg-query -W -f='${Status}' springscan 2>/dev/null | grep -q "install ok installed"; then
  echo "package-check: springscan is already installed here; not touching it" >&2
  exit 2
fi
purge() { "${sudo_cmd[@]}" dpkg --purge springscan >/dev/null || true; }
trap purge EXIT
echo "== dpkg -i $(basename "$deb")"
"${sudo_cmd[@]}" dpkg -i "$deb"
getent passwd springscan >/dev/null || { echo "package-check: no user springscan" >&2; exit 1; }
getent group springscan >/dev/null || { echo "package-check: no group springscan" >&2; exit 1; }
for f in /usr/bin/springscand /usr/bin/springscan /usr/lib/springscan/springscan-commands \
         "$config" "$unit" \
         /lib/udev/rules.d/99-springscan.rules /usr/share/springscan/demo/hat-profile.step \
         /usr/share/doc/springscan/modbus-register-map.md; do
  [[ -e "$f" ]] || { echo "package-check: $f is not installed" >&2; exit 1; }
done
echo "== springscand --check --config $config"
/usr/bin/springscand --check --config "$config"
# As the service runs it: its user must be able to read the config and the demo part.
if command -v runuser >/dev/null && [[ $(id -u) -eq 0 ]]; then
  runuser -u springscan -- /usr/bin/springscand --check --config "$config"
fi
/usr/bin/springscand --version
echo "== springscan version, match, model --help"
/usr/bin/springscan version
work=$(mktemp -d)
printf '0 0 0\n10 0 0\n' >"$work/model.xyz"
printf '10.1 0 0\n0.1 0 0\n' >"$work/scan.xyz"
/usr/bin/springscan match --model "$work/model.xyz" --scan "$work/scan.xyz" --out "$work/pairs.csv"
grep -qx '0,1,0.010000000000000002' "$work/pairs.csv" ||
  { echo "package-check: springscan match paired wrongly" >&2; cat "$work/pairs.csv" >&2; exit 1; }
# Through a file: `grep -q` would stop reading at its match and the writer die of SIGPIPE.
/usr/bin/springscan model --help >"$work/model_help"
grep -q '^usage: springscan model' "$work/model_help" ||
  { echo "package-check: springscan model --help (springscan-commands) failed" >&2; exit 1; }
rm -rf "$work"
status=0
/usr/bin/springscan model 2>/dev/null || status=$?
[[ $status -eq 2 ]] || { echo "package-check: springscan model without a file exited $status, not 2" >&2; exit 1; }
echo "== systemd-analyze verify $unit"
verify=$(systemd-analyze verify "$unit" 2>&1) || { echo "$verify" >&2; exit 1; }
if [[ -n "$verify" ]]; then
  echo "$verify" >&2
  echo "package-check: systemd-analyze verify printed warnings" >&2
  exit 1
fi
echo "== dpkg --purge springscan"
trap - EXIT
"${sudo_cmd[@]}" dpkg --purge springscan
for f in /usr/bin/springscand /usr/bin/springscan /usr/lib/springscan "$config" "$unit" \
         /usr/share/doc/springscan; do
  [[ ! -e "$f" ]] || { echo "package-check: $f is left after purge" >&2; exit 1; }
done
echo "package-check: OK"
