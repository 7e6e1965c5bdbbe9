#!/usr/bin/env bash
# The short fault matrix of CI (issue 19): scripts/fault_matrix.sh with seven of its faults (a
# camera that stops for 2 s, one that switches size, one whose tf goes missing, the clock
# jumping back 30 s, the background relearned with the person in view, the room server
# restarted, a nodelet reloaded) against the running pipeline at 6 fps. One JUnit test case per
# fault, each with its own assertions (fault_matrix.py: no crash, recovery within 20 s, the
# cause reported, at most 3 sets lost where the pipeline should carry on). The whole matrix:
# docs/fault_matrix.md. Writes the JUnit result file (argument 1).
set -u
RESULT="$1"
HERE="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
ROOT="$(cd "$HERE/../../.." && pwd)"
WORK="$(mktemp -d /tmp/tabletop_faults_XXXXXX)"
mkdir -p "$(dirname "$RESULT")"
rm -f "$RESULT"
LOG="$WORK/fault_matrix.log"
export PATH=/usr/bin:/bin:$PATH
bash "$ROOT/scripts/fault_matrix.sh" --no-setup --fps 6 --baseline 3 --out "$WORK" --junit "$RESULT" \
  --only camera_stops,size_switch,tf_missing,clock_back,person_at_learning,room_server_restart,nodelet_reload \
  > "$LOG" 2>&1
rc=$?
cat "$LOG"
if [ ! -s "$RESULT" ]; then
  # The matrix never ran its faults (the pipeline did not start): one failing case says why.
  fail=$(grep -E 'never started|Error|error' "$LOG" | head -n 3 | tr '\n' ' ')
  # shellcheck source=script_junit.sh
  source "$HERE/script_junit.sh"
  script_junit "$RESULT" fault_matrix pipeline_starts "${fail:-fault_matrix.sh exited with $rc}" \
    "$LOG" "$WORK/launch.log"
fi
[ "$rc" -eq 0 ] && rm -rf "$WORK"
exit 0
