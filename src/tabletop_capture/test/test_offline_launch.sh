#!/usr/bin/env bash
# Integration test of launch/offline.launch: renders a small Bayer bag with render_bag, plays it
# through the pipeline with `roslaunch launch/offline.launch` and checks that the launch ends
# by itself when the bag ends and that every frame set of the bag came out of the synchroniser.
# Writes a JUnit result file (argument 1) so catkin_test_results counts it.
set -u
RESULT="$1"
RENDER_BAG="$2"  # path of the render_bag executable
HERE="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
ROOT="$(cd "$HERE/../../.." && pwd)"
WORK="$(mktemp -d /tmp/tabletop_offline_XXXXXX)"
FRAMES=40
CAMERAS=4
mkdir -p "$(dirname "$RESULT")"

junit() {  # name, failure message (empty = pass), log file
  local fail="$2" body=""
  if [ -n "$fail" ]; then
    body="<failure message=\"$(echo "$fail" | sed 's/&/\&amp;/g; s/</\&lt;/g; s/"/\&quot;/g')\"><![CDATA[$(tail -n 60 "$3" 2>/dev/null)]]></failure>"
  fi
  cat > "$RESULT" <<XML
<?xml version="1.0" encoding="UTF-8"?>
<testsuite name="offline_launch" tests="1" failures="$([ -n "$fail" ] && echo 1 || echo 0)" errors="0">
  <testcase classname="offline_launch" name="$1">$body</testcase>
</testsuite>
XML
}

export PATH=/usr/bin:/bin:$PATH
PORT=$(/usr/bin/python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])')
export ROS_MASTER_URI="http://127.0.0.1:$PORT" ROS_HOSTNAME=127.0.0.1 ROS_LOG_DIR="$WORK/log"
LOG="$WORK/run.log"
name="bag_with_${CAMERAS}_bayer_cameras_plays_through_and_exits"

if ! "$RENDER_BAG" --out "$WORK/test.bag" --frames $FRAMES \
     --cameras $CAMERAS --bayer bayer_grbg8 --empty-frames 5 > "$LOG" 2>&1; then
  junit "$name" "render_bag failed" "$LOG"; exit 0
fi
start=$(date +%s)
# Half speed: the test checks that every frame set comes through, not the speed; on a loaded
# 2-core CI machine the whole pipeline (psfs, mpf, mesher) at full speed can make one camera's
# image miss the synchroniser's 0.2 s timeout.
timeout 120 roslaunch -p "$PORT" "$ROOT/launch/offline.launch" bag:="$WORK/test.bag" \
  cameras:=$CAMERAS rate:=0.5 output_dir:="$WORK/out" >> "$LOG" 2>&1
rc=$?
took=$(( $(date +%s) - start ))
echo "[offline_launch] roslaunch exit $rc after ${took} s" | tee -a "$LOG"
if [ $rc -eq 124 ]; then
  junit "$name" "offline.launch did not exit when the bag ended (killed after 120 s)" "$LOG"
elif [ ! -f "$WORK/out/summary.txt" ]; then
  junit "$name" "no summary.txt written by the monitor" "$LOG"
else
  cat "$WORK/out/summary.txt" >> "$LOG"
  got=$(sed -n 's/^frame sets received *\([0-9]*\).*/\1/p' "$WORK/out/summary.txt")
  echo "[offline_launch] $got of $FRAMES frame sets came through" | tee -a "$LOG"
  if [ "${got:-0}" -ne $FRAMES ]; then
    junit "$name" "expected $FRAMES frame sets through the synchroniser, got ${got:-none}" "$LOG"
  else
    junit "$name" "" "$LOG"
  fi
fi
rm -rf "$WORK"
exit 0
