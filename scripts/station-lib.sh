# One run of the simulated station, shared by scripts/demo.sh and scripts/station-msa.sh (source
# it; it defines functions only). springscand runs under the simulated laser scanner (an
# emulated USB device, so the production libusb driver runs: docs/device-protocol.md) and the
# simulated PLC triggers it over Modbus TCP on loopback.
#
#   station_run BIN OUT CAD SURFACE CYCLES [SCANNER_SIM_ARG...] [-- PLC_SIM_ARG...]
#
# BIN: the build tree; OUT: where the config, station.log, reports/ and model-cache/ go (a store
# that already holds reports is continued, as the daemon does after a restart); CAD: part 1's
# CAD file; SURFACE: the part as produced (springscan-demo-part --surface). The scanner is a
# dual-head laser line scanner, heads tilted by +-30 degrees about the travel, since the demo
# bracket's walls are vertical and a head looking straight down gets no return from them;
# SCANNER_SIM_ARGs come after these and override them. The PLC's output goes to stdout.

station_free_port() {
  python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])'
}

station_write_config() {  # OUT CAD PORT
  cat >"$1/springscand.textproto" <<CONFIG
station_name: "springscan demo"
modbus { bind_address: "127.0.0.1" port: $3 allowed_clients: "127.0.0.1" }
scanner { kind: LASER_LINE timeout_s: 5 }
parts {
  part_id: 1
  name: "motor bracket"
  cad_file: "$2"
  settings {
    verdict { tolerance_mm: 0.5 angle_tolerance_deg: 1.0 }
  }
}
report_dir: "$1/reports"
model_cache_dir: "$1/model-cache"
log_level: "info"
CONFIG
}

station_run() {
  local bin=$1 out=$2 cad=$3 surface=$4 cycles=$5
  shift 5
  local sim_args=() plc_args=()
  while (($# > 0)); do
    if [[ $1 == -- ]]; then
      shift
      plc_args=("$@")
      break
    fi
    sim_args+=("$1")
    shift
  done
  mkdir -p "$out"
  local port
  port=$(station_free_port)
  station_write_config "$out" "$cad" "$port"
  setsid "$bin/simulators/springscan-scanner-sim" --part "$surface" --noise 0.02 \
    --step 0.5 --points 400 --head-tilt 30 --duration 1 "${sim_args[@]}" \
    -- "$bin/daemon/springscand" --config "$out/springscand.textproto" \
    >>"$out/station.log" 2>&1 &
  local station=$!
  # A station left running by a failure here would hold its port: stop it on any exit.
  trap "kill -TERM -- -$station 2>/dev/null || true" EXIT
  local ready=0
  for _ in $(seq 100); do  # wait until springscand listens
    if (exec 3<>"/dev/tcp/127.0.0.1/$port") 2>/dev/null; then
      ready=1
      break
    fi
    kill -0 "$station" 2>/dev/null || break
    sleep 0.1
  done
  if ((ready == 0)); then
    cat "$out/station.log"
    echo "station: springscand did not start (log above)" >&2
    return 1
  fi
  local status=0
  "$bin/simulators/springscan-plc-sim" --port "$port" --cycles "$cycles" --parts 1 \
    --timeout 120 "${plc_args[@]}" || status=$?
  kill -TERM -- "-$station" 2>/dev/null || true
  wait "$station" 2>/dev/null || true
  trap - EXIT
  return "$status"
}
