# Sourced by soak.sh and fault_matrix.sh: prepares a run, starts launch/demo.launch in the
# background in its own process group (log in $1/launch.log), waits for its ROS master, and
# stops it again.
#   prepare_run               OUT made absolute and created; setup.sh unless SETUP=false; the
#                             ROS environment (ros_env.sh), logs into $OUT/ros_log; PORT: a
#                             free port for the room server
#   start_pipeline OUT_DIR roslaunch_args...   sets LAUNCH (roslaunch's PID) and a trap
#   stop_pipeline                              roslaunch first (it stops its nodes in order; a
#                                              node signalled on its own would be reported as
#                                              "process has died"), the whole group if it hangs
# Needs ROS_PORT (ros_env.sh).
prepare_run() {
  mkdir -p "$OUT"
  OUT="$(cd "$OUT" && pwd)"
  [ "$SETUP" = false ] || bash "$ROOT/scripts/setup.sh"
  # shellcheck source=ros_env.sh
  source "$ROOT/scripts/ros_env.sh"
  export ROS_LOG_DIR="$OUT/ros_log" ROSCONSOLE_STDOUT_LINE_BUFFERED=1
  PORT=$(free_port)
}

start_pipeline() {
  local out="$1"
  shift
  setsid roslaunch -p "$ROS_PORT" "$ROOT/launch/demo.launch" frames:=0 "$@" >"$out/launch.log" 2>&1 &
  LAUNCH=$!
  trap stop_pipeline EXIT
  for _ in $(seq 1 60); do
    rostopic list >/dev/null 2>&1 && return 0
    sleep 1
  done
  echo "[pipeline] no ROS master after 60 s (see $out/launch.log)" >&2
  return 1
}

stop_pipeline() {
  kill -INT "$LAUNCH" 2>/dev/null || true
  for _ in $(seq 1 30); do
    kill -0 "$LAUNCH" 2>/dev/null || { trap - EXIT; return 0; }
    sleep 1
  done
  kill -KILL -- "-$LAUNCH" 2>/dev/null || true
  trap - EXIT
}
