#!/usr/bin/env bash
# Fault matrix (issue 19): runs the whole pipeline on the simulated rig (launch/demo.launch) at
# the camera rate and injects faults one after the other while it runs (scripts/fault_matrix.py:
# a camera that stops, switches encoding or size, sends NaN calibration, loses or changes its
# tf; the clock jumping back; the background relearned with the person in view; the light
# switched on; the room server restarted; a nodelet
# reloaded). Writes fault_matrix.md / .csv and the
# launch log into the output folder; exits 0 when nothing crashed and everything recovered.
set -eo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"

usage() {
  cat <<'USAGE'
Usage: scripts/fault_matrix.sh [options] [extra roslaunch arg:=value ...]
  --out DIR       output folder (default ./fault_matrix)
  --fps N         camera rate of the simulated rig (default 10: a rate a 2-core machine keeps
                  up with, so that losses are the faults' and not the machine's)
  --only A,B      only these faults (camera_stops, encoding_switch, size_switch,
                  camera_info_nan, tf_missing, tf_change, clock_back,
                  person_at_learning, light_on, room_server_restart, nodelet_reload)
  --baseline S    seconds of normal running before each fault (default 6)
  --junit FILE    also write a JUnit file, one test case per fault
  --no-setup      do not run scripts/setup.sh first
  -h, --help      this text
USAGE
}
OUT="$PWD/fault_matrix"
FPS=10
ONLY=""
SETUP=true
BASELINE=6
JUNIT=""
EXTRA=()
while [ $# -gt 0 ]; do
  case "$1" in
    --out) OUT="$2"; shift 2 ;;
    --fps) FPS="$2"; shift 2 ;;
    --only) ONLY="$2"; shift 2 ;;
    --no-setup) SETUP=false; shift ;;
    --baseline) BASELINE="$2"; shift 2 ;;
    --junit) JUNIT="$2"; shift 2 ;;
    -h|--help) usage; exit 0 ;;
    *:=*) EXTRA+=("$1"); shift ;;
    *) echo "fault_matrix: unknown option '$1'" >&2; usage >&2; exit 2 ;;
  esac
done
# shellcheck source=pipeline_launch.sh
source "$ROOT/scripts/pipeline_launch.sh"
prepare_run
export TABLETOP_ROOT="$ROOT"
echo "[fault_matrix] $(lscpu | sed -n 's/^Model name: *//p'), $(nproc) cores; rig at $FPS fps; output in $OUT"
start_pipeline "$OUT" lockstep:=0 fps:="$FPS" cve_port:="$PORT" "${EXTRA[@]}"
set +e
/usr/bin/python3 "$ROOT/scripts/fault_matrix.py" --pid "$LAUNCH" --out "$OUT" --room-port "$PORT" \
  --log "$OUT/launch.log" --baseline "$BASELINE" \
  ${ONLY:+--only "$ONLY"} ${JUNIT:+--junit "$JUNIT"}
rc=$?
set -e
stop_pipeline
exit "$rc"
