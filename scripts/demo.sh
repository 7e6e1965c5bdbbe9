#!/usr/bin/env bash
# README command 1: sets everything up if needed, then runs the pipeline on the simulated rig,
# headless, with a live status line and a closing summary; writes the contact sheet of the
# camera views and summary.txt to the output folder.
set -eo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"

usage() {
  cat <<'USAGE'
Usage: scripts/demo.sh [options] [extra roslaunch arg:=value ...]
  --frames N        frame sets to render, the empty background frames included (default 300;
                    0 = until Ctrl-C, e.g. to watch the room in a browser)
  --out DIR         output folder (default ./output)
  --cameras N       simulated cameras (default 8)
  --script NAME     motion script: all, wave, point, fold_hands, reach_targets, leave_reenter,
                    head_turn, static (default all)
  --seed N          seed of the sensor noise (default 1)
  --bayer ENC       publish Bayer images (e.g. bayer_rggb8) instead of rgb8
  --scenario NAME   world and sensors: default, a preset (dark_skin, pale_skin, skin_sleeves,
                    cuffs, short_sleeves, four_cameras, vga, lights_on, flicker, clutter,
                    occluder, low_light) or random-SEED, e.g. random-7 (default: default)
  --short-sleeves   bare forearms
  --participants N  1, or 2: a second simulated rig (script reach_targets, seed 2) joins the CVE room
  --port N          port of the CVE room server and its browser client (default 8765)
  --no-cve          no room server, no streaming of the hands
  --no-lockstep     the simulated rig renders at 25 fps whatever the pipeline does, like real
                    cameras: when the machine cannot keep up, pSfS drops whole frame sets and
                    sheds load (the summary says how many). By default the rig waits for the
                    pipeline and runs at the rate the machine sustains (the summary prints it).
  --browser         also open the room in headless Chromium while the pipeline runs: writes
                    cve_room.png and adds its render rate and capture->render latency to the
                    summary (costs the pipeline CPU time: software WebGL)
  --rviz            also open rviz (under Xvfb with a screenshot in the output folder when
                    there is no $DISPLAY)
  --no-mesh-eval    skip the hand-mesh accuracy run after the pipeline (mesh_eval)
  -h, --help        this text
Any NAME:=VALUE is passed to launch/demo.launch (see its argument docs).
USAGE
}

FRAMES=300
OUT="$PWD/output"
RVIZ=false
MESH_EVAL=true
SCENARIO=default
CVE=true
BROWSER=false
PARTICIPANTS=1
PORT=8765
EXTRA=()
while [ $# -gt 0 ]; do
  case "$1" in
    --frames) FRAMES="$2"; shift 2 ;;
    --out) OUT="$2"; shift 2 ;;
    --cameras) EXTRA+=("cameras:=$2"); shift 2 ;;
    --script) EXTRA+=("script:=$2"); shift 2 ;;
    --seed) EXTRA+=("seed:=$2"); shift 2 ;;
    --bayer) EXTRA+=("bayer:=$2"); shift 2 ;;
    --short-sleeves) EXTRA+=("short_sleeves:=true"); shift ;;
    --scenario) SCENARIO="$2"; EXTRA+=("scenario:=$2"); shift 2 ;;
    --participants) PARTICIPANTS="$2"; EXTRA+=("participants:=$2"); shift 2 ;;
    --browser) BROWSER=true; shift ;;
    --port) PORT="$2"; shift 2 ;;
    --no-cve) CVE=false; shift ;;
    --no-lockstep) EXTRA+=("lockstep:=0"); shift ;;
    --rviz) RVIZ=true; shift ;;
    --no-mesh-eval) MESH_EVAL=false; shift ;;
    -h|--help) usage; exit 0 ;;
    *:=*) EXTRA+=("$1"); shift ;;
    *) echo "demo: unknown option '$1'" >&2; usage >&2; exit 2 ;;
  esac
done
mkdir -p "$OUT"
OUT="$(cd "$OUT" && pwd)"

bash "$ROOT/scripts/setup.sh"
# shellcheck source=ros_env.sh
source "$ROOT/scripts/ros_env.sh"
if [ "$SCENARIO" != default ]; then
  # A scenario brings its own cameras: the synchroniser and the monitor must expect that many
  # (a later cameras:= overrides an earlier one given with --cameras).
  SCENARIO_CAMERAS=$("$ROOT/devel/lib/tabletop_sim/describe_scenario" --cameras "$SCENARIO") ||
    { echo "[demo] ERROR: unknown scenario '$SCENARIO' (describe_scenario --list)"; exit 2; }
  EXTRA+=("cameras:=$SCENARIO_CAMERAS")
  "$ROOT/devel/lib/tabletop_sim/describe_scenario" "$SCENARIO"
fi
export ROS_LOG_DIR="$OUT/ros_log"
# Nodelet log lines as they happen, not in one block when the manager exits.
export ROSCONSOLE_STDOUT_LINE_BUFFERED=1

XVFB_PID=""
BROWSER_PID=""
WATCH_PID=""
SHOT_PID=""
cleanup() {
  [ -n "$SHOT_PID" ] && kill "$SHOT_PID" 2>/dev/null || true
  [ -n "$XVFB_PID" ] && kill "$XVFB_PID" 2>/dev/null || true
  [ -n "$BROWSER_PID" ] && kill "$BROWSER_PID" 2>/dev/null || true
  [ -n "$WATCH_PID" ] && kill "$WATCH_PID" 2>/dev/null || true
}
trap cleanup EXIT
if [ "$RVIZ" = true ] && [ -z "${DISPLAY:-}" ]; then
  echo "[demo] no DISPLAY: rviz runs under Xvfb; a screenshot goes to $OUT/rviz.png"
  Xvfb :87 -screen 0 1280x1024x24 >/dev/null 2>&1 &
  XVFB_PID=$!
  export DISPLAY=:87
  ( sleep 15; /usr/bin/import -display :87 -window root "$OUT/rviz.png" 2>/dev/null ) &
  SHOT_PID=$!
fi

echo "[demo] simulated rig -> synchroniser on ROS master $ROS_MASTER_URI; output in $OUT"
if [ "$CVE" = true ]; then
  echo "[demo] CVE room: open http://127.0.0.1:$PORT/ in a browser to see the hands around the" \
    "virtual table (--frames 0 keeps it running until Ctrl-C)"
fi
WEB="$ROOT/src/cvephands_bridge/web"
if [ "$CVE" = true ]; then
  # A viewer in the room: what the bridges stream (rate, kbit/s, capture -> viewer latency).
  "$ROOT/devel/lib/cvephands_bridge/room_watch" --port "$PORT" --wait 20 --interval 0 --decode \
    >"$OUT/room_watch.txt" 2>&1 &
  WATCH_PID=$!
fi
if [ "$BROWSER" = true ]; then
  if [ "$CVE" != true ] || [ ! -x /usr/bin/chromium ] || [ ! -f "$WEB/dist/app.js" ]; then
    echo "[demo] --browser needs the CVE (no --no-cve), /usr/bin/chromium and the built client" >&2
    BROWSER=false
  else
    echo "[demo] headless Chromium joins the room (screenshot: $OUT/cve_room.png)"
    rm -f "$OUT/cve_room.png" "$OUT/browser.json"
    # The rig and the room go on past --frames until the browser check is done (a slow machine
    # shows the hands late), at most 120 s.
    HOLD="$OUT/.browser_check_running"
    touch "$HOLD"
    [ "$FRAMES" != 0 ] && EXTRA+=("rig_frames:=0" "hold_file:=$HOLD")
    ( cd "$WEB" || exit 1
      node test/e2e_browser.mjs --url "http://127.0.0.1:$PORT/?aa=0" \
        --participants "$PARTICIPANTS" --hands 2 --timeout 60 --measure 4 --out "$OUT" \
        --min-fps 0 --max-latency 1e9 >"$OUT/browser.json" 2>"$OUT/browser.log" &
      node_pid=$!
      # The check is done when its result line is written (Chromium may take a while to close).
      while kill -0 "$node_pid" 2>/dev/null && [ ! -s "$OUT/browser.json" ]; do sleep 0.5; done
      rm -f "$HOLD"
      wait "$node_pid" ) &
    BROWSER_PID=$!
  fi
fi
set +e
LIVE=false
[ -t 1 ] && LIVE=true
# Ctrl-C (e.g. with --frames 0) stops roslaunch, which shuts the nodes down; the script and its
# output filters carry on, so the summaries below still get written.
trap 'true' INT
roslaunch -p "$ROS_PORT" "$ROOT/launch/demo.launch" monitor:=true frames:="$FRAMES" \
  output_dir:="$OUT" rviz:="$RVIZ" live_status:="$LIVE" cve:="$CVE" cve_port:="$PORT" \
  "${EXTRA[@]}" 2>&1 |
  (trap '' INT; exec sed -u 's/\x1b\[[0-9;]*m//g; s/\x1b\]2;[^\x07]*\x07//g') |
  (trap '' INT; exec grep --line-buffered -v -E '^(started roslaunch server|SUMMARY|=======|PARAMETERS|NODES|ROS_MASTER_URI|auto-starting|process\[|setting /run_id|core service|logging to|Checking log|Done checking|\s*$| \* /|  /|    [a-z_]+ \()|REQUIRED process|process has finished cleanly|^log file:|Initiating shutdown|killing on exit|shutting down processing monitor|^.{0,8}done.{0,8}$|Loading nodelet|waitForService|Unloading nodelet|Initializing nodelet|Press Ctrl-C|^\.\.\. logging|^.\]2;')
rc=${PIPESTATUS[0]}
if [ -n "$WATCH_PID" ]; then
  kill -INT "$WATCH_PID" 2>/dev/null
  wait "$WATCH_PID" 2>/dev/null
  WATCH_PID=""
  grep '^CVE room' "$OUT/room_watch.txt" | tee -a "$OUT/summary.txt"
fi
if [ -n "$BROWSER_PID" ]; then
  wait "$BROWSER_PID" 2>/dev/null
  BROWSER_PID=""
  [ -f "$OUT/browser_room.png" ] && mv "$OUT/browser_room.png" "$OUT/cve_room.png"
  /usr/bin/python3 - "$OUT/browser.json" <<'PY' | tee -a "$OUT/summary.txt"
import json, sys
try:
    r = json.loads(open(sys.argv[1]).read().strip().splitlines()[-1])
except Exception as e:
    print('browser (headless Chromium): no result (%s); see browser.log' % e)
    sys.exit(0)
s = r.get('stats') or {}
lat = s.get('latencyMs') or {}
def num(x):  # a figure the page could not measure prints as nan
    return x if isinstance(x, (int, float)) else float('nan')
rigs = [p for p in s.get('participants', []) if p.get('role') == 'rig']
print('browser (headless Chromium, software WebGL 960x540): %d participant(s) with %s hands; '
      'render %.1f fps' % (len(rigs), '+'.join(str(p.get('hands', 0)) for p in rigs),
                           num(s.get('renderFps'))))
print('  capture -> browser render latency median %.0f ms, p95 %.0f ms (capture -> room server '
      '%.0f ms); decode %.1f + mesh %.1f ms per hand in the page' % (
          num(lat.get('median')), num(lat.get('p95')),
          num((s.get('captureToServerMs') or {}).get('median')),
          num((s.get('decodeMs') or {}).get('mean')), num((s.get('meshMs') or {}).get('mean'))))
for note in r.get('notes', []):
    print('  browser note: ' + note)
if r.get('failures'):
    print('  browser check: ' + '; '.join(r['failures']))
PY
fi
if [ "$rc" -eq 0 ] && [ "$MESH_EVAL" = true ]; then
  # Hand-mesh accuracy against the simulated truth and a picture of both hands' meshes: the
  # same reconstruction and meshing code as the pipeline, on 4 s of reach_targets.
  echo "[demo] scoring hand meshes against the true hand surface (mesh_eval, ~10 s)"
  "$ROOT/devel/lib/cvephands_bridge/mesh_eval" --scenario "$SCENARIO" --script reach_targets \
    --frames 100 --every 20 \
    --out "$OUT" 2>/dev/null | tee -a "$OUT/summary.txt"
  rc=${PIPESTATUS[0]}
fi
set -e
echo "[demo] files in $OUT: $(cd "$OUT" && ls -1 | grep -v ros_log | tr '\n' ' ')"
exit "$rc"
