#!/usr/bin/env bash
# Installs springscan's Debian 12 build and test dependencies. Idempotent and quick when
# everything is already present: it asks dpkg first and runs apt-get only for what is missing.
set -euo pipefail

packages=(
  # python3: tests/cli/analyze_test.sh reads report.json with it.
  build-essential cmake ninja-build pkg-config ccache git python3
  libeigen3-dev libnanoflann-dev
  libocct-foundation-dev libocct-modeling-data-dev libocct-modeling-algorithms-dev
  libocct-data-exchange-dev libtbb-dev
  # Mesh decimation (vtkDecimatePro; docs/decimation.md: why VTK, and what it costs to install).
  libvtk9-dev
  libprotobuf-dev protobuf-compiler zlib1g-dev
  libusb-1.0-0-dev libmodbus-dev libsystemd-dev libmosquitto-dev
  # springscand's operator page (docs/operator-page.md: why civetweb).
  libcivetweb-dev
  # GenICam 3D line profilers over GigE Vision / USB3 Vision (drivers/genicam/).
  libaravis-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  umockdev libumockdev-dev libglib2.0-dev
)
# The rest is for the tests, CI and benchmarks; the demo (scripts/demo.sh) goes without it.
if [[ "${SPRINGSCAN_WITH_EXTRAS:-1}" == 1 ]]; then
  # scripts/package.sh and package-check.sh: dpkg-shlibdeps for CPack's DEB generator,
  # systemd-analyze verify, adduser for the package's postinst.
  packages+=(dpkg-dev systemd adduser)
  # CI's format check, and the sanitizer and fuzz build (clang with libFuzzer's runtime).
  packages+=(clang-format clang libclang-rt-14-dev)
  # Reference implementations and third-party peers used by tests and benchmarks.
  packages+=(mbpoll python3-scipy python3-numpy)
  # The third-party PLC client test (tests/daemon/pymodbus_plc.py): Debian 12's pymodbus 3.0.
  # Its client imports serial_asyncio, which Debian only recommends (we install without them).
  packages+=(python3-pymodbus python3-serial-asyncio)
  # The HTML report is checked in a real browser (tests/report/browser_test.cpp).
  packages+=(chromium)
  # Results to the plant over MQTT: a real broker, a third-party subscriber, test certificates.
  packages+=(mosquitto python3-paho-mqtt openssl)
fi

missing=()
for p in "${packages[@]}"; do
  status=$(dpkg-query -W -f='${Status}' "$p" 2>/dev/null || true)
  [[ "$status" == "install ok installed" ]] || missing+=("$p")
done
if ((${#missing[@]} == 0)); then
  exit 0
fi

echo "install-deps: installing ${missing[*]}" >&2
sudo_cmd=()
if [[ $(id -u) -ne 0 ]]; then sudo_cmd=(sudo); fi
export DEBIAN_FRONTEND=noninteractive
"${sudo_cmd[@]}" apt-get update -qq
"${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
