#!/usr/bin/env bash
# Soak (issue 19): runs the whole pipeline on the simulated rig (launch/demo.launch: rig,
# synchroniser, pSfS, MPF, PAPF, meshes, room server and bridge) for a long time and judges it
# with scripts/soak_monitor.py: resident memory flat after the warm-up (fitted growth < 1 %),
# under 1.5 GB in all, no queue beyond its size, no /diagnostics status at ERROR or STALE.
# Writes soak.csv, soak.svg, soak_summary.txt and the launch log into the output folder; exits
# 0 when the soak passes.
set -eo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"

usage() {
  cat <<'USAGE'
Usage: scripts/soak.sh [options] [extra roslaunch arg:=value ...]
  --minutes M     length (default 60)
  --warmup S      seconds not judged at the start: background learning, caches (default 300)
  --interval S    seconds between samples (default 10)
  --out DIR       output folder (default ./soak)
  --camera-rate   the simulated cameras run at 25 fps whatever the pipeline does, like real
                  ones (a machine that cannot keep up drops frame sets: those WARNs are listed,
                  not failed). Default: lockstep, every frame set is processed at the rate the
                  machine sustains, so the pipeline is fully loaded all along.
  --max-growth P  RSS growth bar after the warm-up, percent (default 1)
  --no-setup      do not run scripts/setup.sh first (the tests' short soak)
  -h, --help      this text
The rig loops its motion script (all) for as long as the soak runs.
USAGE
}

MINUTES=60
WARMUP=300
INTERVAL=10
OUT="$PWD/soak"
LOCKSTEP=2
SETUP=true
GROWTH=1
EXTRA=()
while [ $# -gt 0 ]; do
  case "$1" in
    --minutes) MINUTES="$2"; shift 2 ;;
    --warmup) WARMUP="$2"; shift 2 ;;
    --interval) INTERVAL="$2"; shift 2 ;;
    --out) OUT="$2"; shift 2 ;;
    --camera-rate) LOCKSTEP=0; shift ;;
    --no-setup) SETUP=false; shift ;;
    --max-growth) GROWTH="$2"; shift 2 ;;
    -h|--help) usage; exit 0 ;;
    *:=*) EXTRA+=("$1"); shift ;;
    *) echo "soak: unknown option '$1'" >&2; usage >&2; exit 2 ;;
  esac
done
# shellcheck source=pipeline_launch.sh
source "$ROOT/scripts/pipeline_launch.sh"
prepare_run

echo "[soak] $(lscpu | sed -n 's/^Model name: *//p'), $(nproc) cores; $MINUTES min on ROS master" \
  "$ROS_MASTER_URI, $([ "$LOCKSTEP" = 0 ] && echo 'camera rate (25 fps)' || echo lockstep); output in $OUT"
start_pipeline "$OUT" lockstep:="$LOCKSTEP" cve_port:="$PORT" "${EXTRA[@]}"
QUEUE=$(sed -n 's/^ *queue_size: *\([0-9]*\).*/\1/p' "$ROOT/src/psfs_reconstruction/config/psfs.yaml" | head -n 1)
set +e
/usr/bin/python3 "$ROOT/scripts/soak_monitor.py" --pid "$LAUNCH" --minutes "$MINUTES" \
  --warmup "$WARMUP" --interval "$INTERVAL" --out "$OUT" --queue "${QUEUE:-2}" \
  --max-growth "$GROWTH"
rc=$?
set -e
stop_pipeline
if grep -q -E 'process has died|Segmentation fault|terminate called' "$OUT/launch.log"; then
  echo "[soak] FAIL: a process died (see $OUT/launch.log):"
  grep -E 'process has died|Segmentation fault|terminate called' "$OUT/launch.log" | head -n 5
  echo "FAIL: a process died" >> "$OUT/soak_summary.txt"
  rc=1
fi
echo "[soak] $(tail -n 1 "$OUT/soak_summary.txt"): $OUT/soak_summary.txt, soak.svg, soak.csv"
exit "$rc"
