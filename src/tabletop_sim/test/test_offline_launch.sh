#!/usr/bin/env bash
# Integration test of launch/offline.launch: renders a small Bayer bag with render_bag (25 empty
# sets, then the person), plays it through the whole pipeline with `roslaunch
# launch/offline.launch` twice, at full rate and at 0.4x, and checks for each run that the
# launch ends by itself once the pipeline has processed the bag, that every frame set came out
# of the synchroniser and was reconstructed after the learning sets, and that both runs gave
# the SAME volumes, hand volumes and targets (digests.txt: CRC-32 per volume): offline results
# do not depend on the playback rate or on the machine's speed. A third run plays the bag twice
# with one roscore and one pipeline (time goes back between the passes, as with a second
# `rosbag play` or `rosbag play -l`): the synchroniser, pSfS and the tracker start over, and
# the second pass must give the same digests as a first play.
# Writes a JUnit result file (argument 1) so catkin_test_results counts it.
set -u
RESULT="$1"
RENDER_BAG="$2"  # path of the render_bag executable
HERE="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
ROOT="$(cd "$HERE/../../.." && pwd)"
WORK="$(mktemp -d /tmp/tabletop_offline_XXXXXX)"
FRAMES=45
EMPTY=25
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
PORT=$(/usr/bin/python3 "$ROOT/scripts/free_port.py")
export ROS_MASTER_URI="http://127.0.0.1:$PORT" ROS_HOSTNAME=127.0.0.1 ROS_LOG_DIR="$WORK/log"
LOG="$WORK/run.log"
name="bag_with_${CAMERAS}_bayer_cameras_gives_the_same_results_at_any_rate_and_when_played_twice"

if ! "$RENDER_BAG" --out "$WORK/test.bag" --frames $FRAMES --script reach_targets \
     --cameras $CAMERAS --bayer bayer_grbg8 --empty-frames $EMPTY > "$LOG" 2>&1; then
  junit "$name" "render_bag failed" "$LOG"; exit 0
fi

# The second run gets a quarter of the CPU where cgroups allow it (root), else runs as is.
THROTTLE=()
if bash "$ROOT/scripts/throttled.sh" true >> "$LOG" 2>&1; then
  THROTTLE=(bash "$ROOT/scripts/throttled.sh")
else
  echo "[offline_launch] no cgroup CPU quota here (not root?): the 0.4x run is not throttled" | tee -a "$LOG"
fi

# One run; prints an error and returns 1 when the run itself went wrong.
run() {  # rate, output dir, command prefix...
  local start rc took got rate="$1" out="$2"
  shift 2
  start=$(date +%s)
  # Generous limit: with a quarter of a slow machine's CPU a set takes about a second.
  timeout 300 "$@" roslaunch -p "$PORT" "$ROOT/launch/offline.launch" bag:="$WORK/test.bag" \
    cameras:=$CAMERAS rate:="$rate" output_dir:="$out" digests:=true plays:="${PLAYS:-1}" >> "$LOG" 2>&1
  rc=$?
  took=$(( $(date +%s) - start ))
  echo "[offline_launch] rate $rate: roslaunch exit $rc after ${took} s" | tee -a "$LOG"
  if [ $rc -eq 124 ]; then
    FAIL="offline.launch at rate $rate did not exit after the bag (killed after 300 s)"; return 1
  fi
  if [ ! -f "$out/summary.txt" ] || [ ! -f "$out/digests.txt" ]; then
    FAIL="rate $rate: no summary.txt or digests.txt written by the monitor"; return 1
  fi
  cat "$out/summary.txt" >> "$LOG"
  # What pSfS did with each set, from psfs/processed (the monitor's own frame count may miss a
  # set on a loaded machine: it is another process with a short queue).
  got=$(grep -c ' psfs ' "$out/digests.txt")
  learned=$(grep -c ' psfs learned' "$out/digests.txt")
  echo "[offline_launch] rate $rate: $got of $FRAMES frame sets reached pSfS, $learned learned" | tee -a "$LOG"
  if [ "${got:-0}" -ne $FRAMES ] || [ "$learned" -ne $EMPTY ]; then
    FAIL="rate $rate: expected $FRAMES frame sets at pSfS ($EMPTY learned), got ${got:-none} ($learned)"; return 1
  fi
  got=$(grep -c ' body ' "$out/digests.txt")
  if [ "$got" -ne $((FRAMES - EMPTY)) ]; then
    FAIL="rate $rate: expected $((FRAMES - EMPTY)) body volumes (every set after the learning sets), got $got"
    return 1
  fi
  return 0
}

FAIL=""
if run 1.0 "$WORK/out_full" && run 0.4 "$WORK/out_slow" "${THROTTLE[@]}"; then
  if ! diff "$WORK/out_full/digests.txt" "$WORK/out_slow/digests.txt" >> "$LOG" 2>&1; then
    FAIL="the runs at rate 1.0 and 0.4 (throttled: ${#THROTTLE[@]}) gave different volumes or targets (digests.txt differ)"
  else
    echo "[offline_launch] both runs gave identical volumes, hand volumes and targets" \
      "($(wc -l < "$WORK/out_full/digests.txt") sets)" | tee -a "$LOG"
  fi
fi
if [ -z "$FAIL" ] && PLAYS=2 run 1.0 "$WORK/out_twice"; then
  if [ ! -f "$WORK/out_twice/digests_play2.txt" ]; then
    FAIL="bag played twice: the second pass gave nothing (no digests_play2.txt)"
  elif ! diff "$WORK/out_full/digests.txt" "$WORK/out_twice/digests_play2.txt" >> "$LOG" 2>&1; then
    FAIL="bag played twice: the second pass gave other volumes or targets than a first play"
  elif ! diff "$WORK/out_full/digests.txt" "$WORK/out_twice/digests.txt" >> "$LOG" 2>&1; then
    FAIL="bag played twice: the first pass differs from a single play"
  elif ! grep -q "time went back" "$LOG"; then
    FAIL="bag played twice: no stage said that time went back"
  else
    echo "[offline_launch] bag played twice: both passes identical to a single play" \
      "($(wc -l < "$WORK/out_twice/digests_play2.txt") sets in the second)" | tee -a "$LOG"
  fi
fi
junit "$name" "$FAIL" "$LOG"
[ -n "${KEEP_WORK:-}" ] || rm -rf "$WORK"
exit 0
