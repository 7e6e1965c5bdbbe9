#!/usr/bin/env bash
# Runs a command with the CPU cut to a fraction of the machine, to prove that the test suite
# and the pipeline do not depend on the machine's speed (issue: slower machines). Uses a cgroup
# CPU quota (cgroup v2 cpu.max or v1 cpu.cfs_quota_us); needs root.
#   scripts/throttled.sh [--cpus X] COMMAND [ARGS...]
#     --cpus X   CPU time the command and its children get, in cores (default: a quarter of
#                the machine's cores, e.g. 0.5 on 2 cores)
# Example: sudo bash scripts/throttled.sh bash scripts/test.sh
set -eo pipefail
CORES=$(nproc)
CPUS=$(awk -v n="$CORES" 'BEGIN { printf "%.3f", n / 4 }')
if [ "${1:-}" = "--cpus" ]; then CPUS="$2"; shift 2; fi
if [ $# -eq 0 ]; then sed -n '2,8p' "$0"; exit 2; fi
PERIOD=100000
QUOTA=$(awk -v c="$CPUS" -v p="$PERIOD" 'BEGIN { printf "%d", c * p }')
NAME="tabletop_throttle_$$"
if [ -f /sys/fs/cgroup/cgroup.controllers ]; then            # cgroup v2
  DIR=/sys/fs/cgroup/$NAME
  mkdir "$DIR"
  echo "$QUOTA $PERIOD" > "$DIR/cpu.max"
elif [ -d /sys/fs/cgroup/cpu ]; then                          # cgroup v1
  DIR=/sys/fs/cgroup/cpu/$NAME
  mkdir "$DIR"
  echo "$PERIOD" > "$DIR/cpu.cfs_period_us"
  echo "$QUOTA" > "$DIR/cpu.cfs_quota_us"
else
  echo "throttled: no cgroup cpu controller found under /sys/fs/cgroup" >&2
  exit 1
fi
cleanup() {
  # Move ourselves out, then remove the group (it must be empty).
  if [ -f /sys/fs/cgroup/cgroup.controllers ]; then echo $$ > /sys/fs/cgroup/cgroup.procs; else echo $$ > /sys/fs/cgroup/cpu/cgroup.procs; fi
  rmdir "$DIR" 2>/dev/null || true
}
trap cleanup EXIT
echo $$ > "$DIR/cgroup.procs"
echo "[throttled] $CPUS of $CORES cores (cgroup $DIR, quota $QUOTA us per $PERIOD us): $*"
start=$(date +%s)
set +e
"$@"
rc=$?
set -e
echo "[throttled] exit $rc after $(( $(date +%s) - start )) s with $CPUS of $CORES cores"
exit $rc
