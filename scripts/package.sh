#!/usr/bin/env bash
# Builds the station's Debian package (CPack DEB, cmake/Install.cmake): springscand and
# springscan in /usr/bin (with springscan-commands, which springscan runs, in /usr/lib/springscan),
# the unit /lib/systemd/system/springscand.service, the udev rule
# /lib/udev/rules.d/99-springscan.rules, the default config /etc/springscan/springscand.textproto
# (a conffile) naming the demo part in /usr/share/springscan/demo, the docs in
# /usr/share/doc/springscan, and a postinst that creates the system user and group springscan.
#   scripts/package.sh [BUILD_DIR]     default build-pkg/ (Release, no tests, no simulators)
# Builds only the programs (incremental; ccache when present), then prints the .deb's path.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
dir=${1:-$root/build-pkg}
command -v dpkg-shlibdeps >/dev/null || { echo "package: dpkg-shlibdeps missing (dpkg-dev)" >&2; exit 2; }
mapfile -t launcher < <(bash "$root/scripts/ccache-launcher.sh")
generator=()
if [[ ! -f "$dir/CMakeCache.txt" ]] && command -v ninja >/dev/null; then generator=(-G Ninja); fi
# The package's paths (/usr, /etc, /lib); install (and so cpack) builds only what it installs.
cmake -S "$root" -B "$dir" "${generator[@]}" -DCMAKE_BUILD_TYPE=Release "${launcher[@]}" \
  -DCMAKE_INSTALL_PREFIX=/usr -DCMAKE_SKIP_INSTALL_ALL_DEPENDENCY=ON \
  -DSPRINGSCAN_BUILD_TESTS=OFF -DSPRINGSCAN_BUILD_BENCHMARKS=OFF -DSPRINGSCAN_BUILD_SIMULATORS=OFF \
  >/dev/null
cmake --build "$dir" --parallel "$(nproc)" --target springscand springscan springscan-commands
out="$dir/package"
rm -rf "$out" && mkdir -p "$out"
(cd "$dir" && cpack -G DEB -B "$out" >"$out/cpack.log") || { cat "$out/cpack.log" >&2; exit 1; }
rm -rf "$out/_CPack_Packages"
deb=$(ls "$out"/springscan_*.deb)
dpkg-deb --info "$deb" >/dev/null
echo "$deb"
