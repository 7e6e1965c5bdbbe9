#!/usr/bin/env bash
# The short fault matrix of CI (issue 19): scripts/fault_matrix.sh with four of its faults (a
# camera that stops for 2 s, one that switches size, the room server restarted, a nodelet
# reloaded) against the running pipeline at 6 fps. Passes when nothing crashed and the
# pipeline recovered from each within 20 s. The whole matrix: docs/fault_matrix.md.
# Writes a JUnit result file (argument 1).
set -u
RESULT="$1"
HERE="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
ROOT="$(cd "$HERE/../../.." && pwd)"
WORK="$(mktemp -d /tmp/tabletop_faults_XXXXXX)"
mkdir -p "$(dirname "$RESULT")"
LOG="$WORK/fault_matrix.log"
export PATH=/usr/bin:/bin:$PATH
bash "$ROOT/scripts/fault_matrix.sh" --no-setup --fps 6 --baseline 3 --out "$WORK" \
  --only camera_stops,size_switch,room_server_restart,nodelet_reload > "$LOG" 2>&1
rc=$?
cat "$LOG"
fail=""
if [ "$rc" -ne 0 ]; then
  fail=$(grep -E 'recovered no|crash YES|never started' "$LOG" | head -n 3 | tr '\n' ' ')
  fail=${fail:-"fault_matrix.sh exited with $rc"}
fi
# shellcheck source=script_junit.sh
source "$HERE/script_junit.sh"
script_junit "$RESULT" fault_matrix \
  camera_stop_size_switch_room_server_restart_nodelet_reload_recover_without_crash "$fail" \
  "$LOG" "$WORK/launch.log"
[ "$rc" -eq 0 ] && rm -rf "$WORK"
exit 0
