#!/usr/bin/env bash
# The layout and arrows of DESIGN.md, checked on the source tree (a CTest test, so a change that
# breaks them fails the suite): what each folder may include, and where OpenCASCADE and the
# generated protobuf header may be seen. Usage: tests/layout_test.sh SOURCE_ROOT
set -uo pipefail
cd "${1:?usage: layout_test.sh SOURCE_ROOT}" || exit 2
failures=0
violation() {  # rule, offending lines
  if [[ -n "$2" ]]; then
    printf 'layout: %s\n%s\n' "$1" "$2"
    failures=$((failures + 1))
  fi
}
sources() { find "$@" -type f \( -name '*.cpp' -o -name '*.hpp' \) | sort; }

violation "no source file at analysis/'s root: each belongs to the folder of its stage" \
  "$(find analysis -maxdepth 1 -type f \( -name '*.cpp' -o -name '*.hpp' \))"
violation "analysis/ includes no driver, daemon, report or simulator header" \
  "$(sources analysis | xargs grep -nE '#include "(drivers|daemon|report|simulators)/' || true)"
violation "analysis/ sees no device, socket, Modbus, USB or systemd header" \
  "$(sources analysis | xargs grep -nE '#include <(libusb|modbus|systemd|sys/socket|netinet)' || true)"
violation "the generated proto header only in analysis/messages/ and the pipeline's result type" \
  "$(sources analysis | grep -vE '^analysis/(messages/|inspection/pipeline\.(hpp|cpp))' |
     xargs grep -n '"proto/springscan.pb.h"' || true)"
violation "OpenCASCADE only in analysis/cad/ (and the test parts' profile, cutout and artefact solids)" \
  "$(sources analysis drivers daemon report cli simulators |
     grep -vE '^(analysis/cad/|simulators/parts/(cad_profile|sheet_cutouts|artefact)\.cpp)' |
     xargs grep -nE '#include <[A-Za-z0-9]+_[A-Za-z0-9_]*\.hxx>|#include <(gp|TopoDS|Standard)[A-Za-z_]*\.hxx>' || true)"
violation "VTK only in analysis/preprocess/decimation.cpp (the mesh decimation's adapter)" \
  "$(sources analysis drivers daemon report cli simulators |
     grep -v '^analysis/preprocess/decimation\.cpp$' |
     xargs grep -nE '#include <vtk[A-Za-z0-9_]*\.h>' || true)"
violation "drivers/ use only analysis/core/" \
  "$(sources drivers | xargs grep -nE '#include "analysis/' | grep -v '"analysis/core/' || true)"
violation "the product never includes the test parts (simulators/parts/)" \
  "$(sources analysis drivers daemon report cli | xargs grep -n '"simulators/parts/' || true)"
violation "tests mirror the source tree: every tests/analysis/<stage>/ has its stage folder" \
  "$(for d in tests/analysis/*/; do s=${d#tests/}; [[ -d "$s" ]] || echo "$d"; done)"

if ((failures > 0)); then
  echo "layout: $failures rule(s) broken (DESIGN.md, Layout)"
  exit 1
fi
echo "layout: every rule holds"
