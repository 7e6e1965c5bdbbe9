#!/usr/bin/env bash
# Integration test of the install space: installs the already built workspace (argument 2: its
# build folder, e.g. <ws>/build) into a temporary root (DESTDIR; the install prefix configured
# by catkin_make, <ws>/install, below it: catkin's setup files find their folder themselves, so
# the copy works where it lies), then, in a clean environment (env -i, PATH=/usr/bin:/bin, HOME)
# that sources only <install>/setup.bash, checks
#   rospack_finds_every_package   rospack find gives <install>/share/<pkg> for every package;
#   room_server_serves_client     the installed room_server, started WITHOUT --static, finds the
#                                 installed browser client and serves index.html and app.js on
#                                 a free loopback port (skipped when web/dist was not built);
#   offline_launch_plays_bag      <install>/share/tabletop_sim/launch/offline.launch plays a bag
#                                 rendered by the installed render_bag and exits by itself, with
#                                 every frame set through pSfS (digests.txt);
#   demo_launch_starts            the installed demo.launch runs a short simulated session (rig,
#                                 pipeline, room server, monitor) and exits by itself; its room
#                                 server and rviz config resolve to installed files.
# Writes a JUnit result file (argument 1) so catkin_test_results counts it.
set -u
RESULT="$1"
BUILD="$2"
WORK="$(mktemp -d /tmp/tabletop_install_XXXXXX)"
LOG="$WORK/run.log"
FRAMES=30
EMPTY=25
CAMERAS=4
PKGS="tabletop_msgs tabletop_common tabletop_capture tabletop_sim psfs_reconstruction hand_tracking cvephands_bridge"
mkdir -p "$(dirname "$RESULT")"
export PATH=/usr/bin:/bin:$PATH

CASES=""
FAILED=0
SKIPPED=0
NCASES=0
xml_escape() { sed 's/&/\&amp;/g; s/</\&lt;/g; s/>/\&gt;/g; s/"/\&quot;/g'; }
case_result() {  # name, "" = pass | "FAIL: msg" | "SKIP: msg"
  local body=""
  NCASES=$((NCASES + 1))
  case "$2" in
    FAIL:*)
      FAILED=$((FAILED + 1))
      echo "[install_space] $1: ${2#FAIL: }" | tee -a "$LOG"
      body="<failure message=\"$(echo "${2#FAIL: }" | xml_escape)\"><![CDATA[$(tail -n 40 "$LOG" | sed 's/]]>/]] >/g')]]></failure>" ;;
    SKIP:*)
      SKIPPED=$((SKIPPED + 1))
      echo "[install_space] $1: skipped: ${2#SKIP: }" | tee -a "$LOG"
      body="<skipped message=\"$(echo "${2#SKIP: }" | xml_escape)\"/>" ;;
    *) echo "[install_space] $1: ok" | tee -a "$LOG" ;;
  esac
  CASES="$CASES  <testcase classname=\"install_space\" name=\"$1\">$body</testcase>
"
}
finish() {
  cat > "$RESULT" <<XML
<?xml version="1.0" encoding="UTF-8"?>
<testsuite name="install_space" tests="$NCASES" failures="$FAILED" errors="0" skipped="$SKIPPED">
$CASES</testsuite>
XML
  echo "[install_space] $NCASES checks, $FAILED failed, $SKIPPED skipped; log $LOG" 
  if [ -z "${KEEP_WORK:-}" ] && [ "$FAILED" -eq 0 ]; then rm -rf "$WORK"; fi
  exit 0
}
# A free loopback port below the kernel's ephemeral range (scripts/free_port.py: why).
free_port() {
  /usr/bin/python3 "$(cd "$(dirname "${BASH_SOURCE[0]}")/../../.." && pwd)/scripts/free_port.py"
}

# ---- install ---------------------------------------------------------------------------------
PREFIX=$(sed -n 's/^CMAKE_INSTALL_PREFIX:PATH=//p' "$BUILD/CMakeCache.txt" 2>/dev/null)
if [ -z "$PREFIX" ]; then
  case_result installs "FAIL: no CMAKE_INSTALL_PREFIX in $BUILD/CMakeCache.txt (build the workspace first)"
  finish
fi
INSTALL="$WORK/root$PREFIX"
start=$(date +%s)
# cmake --install builds nothing: the workspace must be built (catkin_make) before. DESTDIR, not
# --prefix: catkin installs its setup files (setup.bash, _setup_util.py, ...) to the absolute
# prefix configured, so `--prefix DIR` would put them into <ws>/install, the rest into DIR.
if ! DESTDIR="$WORK/root" cmake --install "$BUILD" > "$WORK/install.log" 2>&1; then
  tail -n 30 "$WORK/install.log" >> "$LOG"
  case_result installs "FAIL: cmake --install $BUILD failed (is the whole workspace built? catkin_make first)"
  finish
fi
echo "[install_space] installed into $INSTALL in $(( $(date +%s) - start )) s" | tee -a "$LOG"
grep -i 'warning' "$WORK/install.log" | tee -a "$LOG"
if [ ! -f "$INSTALL/setup.bash" ]; then
  case_result installs "FAIL: no setup.bash in $INSTALL"
  finish
fi
case_result installs ""

# A clean environment: nothing of the caller's shell (no devel space, no ROS_PACKAGE_PATH), only
# the install space's setup.bash (under set +u: it fails under set -u).
PORT=$(free_port)
inenv() {  # command string, run by bash in the clean environment
  env -i PATH=/usr/bin:/bin HOME="${HOME:-/tmp}" LANG=C.UTF-8 \
    ROS_MASTER_URI="http://127.0.0.1:$PORT" ROS_HOSTNAME=127.0.0.1 ROS_LOG_DIR="$WORK/log" \
    bash -c "set +u; source '$INSTALL/setup.bash' || exit 99; $1"
}

# ---- rospack --------------------------------------------------------------------------------
fail=""
for p in $PKGS; do
  got=$(inenv "rospack find $p" 2>>"$LOG")
  echo "[install_space] rospack find $p -> $got" >> "$LOG"
  if [ "$got" != "$INSTALL/share/$p" ]; then
    fail="${fail}rospack find $p gave '${got}', not $INSTALL/share/$p; "
  fi
done
case_result rospack_finds_every_package "${fail:+FAIL: $fail}"

# ---- every installed program and library finds its libraries ----------------------------------
# (an installed tool linking a library that is built but not installed fails only when run)
fail=""
for f in "$INSTALL"/lib/*.so "$INSTALL"/lib/*/*; do
  [ -f "$f" ] && head -c 4 "$f" | grep -q "ELF" || continue
  missing=$(inenv "ldd '$f'" 2>>"$LOG" | grep 'not found' | awk '{print $1}' | tr '\n' ' ')
  [ -n "$missing" ] && fail="${fail}$(basename "$f") needs ${missing}; "
done
case_result installed_binaries_link "${fail:+FAIL: $fail}"

# ---- room server ----------------------------------------------------------------------------
DIST="$INSTALL/share/cvephands_bridge/web/dist"
# The browser client in the source tree (scripts/setup.sh builds it with npm after catkin_make).
SRC_DIST="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)/cvephands_bridge/web/dist"
if [ ! -f "$DIST/index.html" ]; then
  if [ ! -f "$SRC_DIST/index.html" ]; then
    case_result room_server_serves_client "SKIP: web/dist was not built (npm unavailable?), so not installed"
  else
    case_result room_server_serves_client "FAIL: $SRC_DIST was built but is not installed in $DIST"
  fi
else
  fail=""
  WPORT=$(free_port)
  # No --static: the server must find the client installed beside it.
  inenv "exec rosrun cvephands_bridge room_server --bind 127.0.0.1 --port $WPORT --status 0" > "$WORK/room_server.log" 2>&1 &
  rs_pid=$!
  for _ in $(seq 1 100); do
    grep -q 'listening' "$WORK/room_server.log" && break
    kill -0 $rs_pid 2>/dev/null || break
    sleep 0.1
  done
  cat "$WORK/room_server.log" >> "$LOG"
  if ! grep -q "client from $DIST" "$WORK/room_server.log"; then
    fail="room_server did not serve the installed client $DIST (see its log above); "
  fi
  for f in index.html app.js; do
    url="http://127.0.0.1:$WPORT/$f"
    [ "$f" = index.html ] && url="http://127.0.0.1:$WPORT/"
    if ! curl -fsS --max-time 10 -o "$WORK/got_$f" "$url" >> "$LOG" 2>&1; then
      fail="${fail}GET $url failed; "
    elif ! cmp -s "$WORK/got_$f" "$DIST/$f"; then
      fail="${fail}GET $url did not return $DIST/$f; "
    fi
  done
  kill $rs_pid 2>/dev/null
  # $rs_pid is the background subshell; the server (env -> bash -> rosrun, each exec'd) is its
  # child and outlives it: stop it by its unique command line.
  pkill -f "room_server --bind 127.0.0.1 --port $WPORT " 2>/dev/null
  wait $rs_pid 2>/dev/null
  case_result room_server_serves_client "${fail:+FAIL: $fail}"
fi

# ---- offline.launch on a bag rendered by the installed render_bag ---------------------------
LAUNCH="$INSTALL/share/tabletop_sim/launch"
fail=""
if ! inenv "rosrun tabletop_sim render_bag --out '$WORK/t.bag' --frames $FRAMES --script reach_targets --cameras $CAMERAS --empty-frames $EMPTY" >> "$LOG" 2>&1; then
  fail="render_bag from the install space failed"
else
  start=$(date +%s)
  inenv "timeout 150 roslaunch -p $PORT '$LAUNCH/offline.launch' bag:='$WORK/t.bag' cameras:=$CAMERAS output_dir:='$WORK/out' digests:=true" >> "$LOG" 2>&1
  rc=$?
  echo "[install_space] offline.launch: exit $rc after $(( $(date +%s) - start )) s" | tee -a "$LOG"
  if [ $rc -eq 124 ]; then
    fail="offline.launch did not exit by itself after the bag (killed after 150 s)"
  elif [ ! -f "$WORK/out/digests.txt" ]; then
    fail="offline.launch (exit $rc) wrote no digests.txt"
  else
    got=$(grep -c ' psfs ' "$WORK/out/digests.txt")
    learned=$(grep -c ' psfs learned' "$WORK/out/digests.txt")
    body=$(grep -c ' body ' "$WORK/out/digests.txt")
    echo "[install_space] offline.launch: $got of $FRAMES sets reached pSfS, $learned learned, $body body volumes" | tee -a "$LOG"
    if [ "$got" -ne $FRAMES ] || [ "$learned" -ne $EMPTY ] || [ "$body" -ne $((FRAMES - EMPTY)) ]; then
      fail="expected $FRAMES sets at pSfS ($EMPTY learned, $((FRAMES - EMPTY)) body volumes), got $got ($learned, $body)"
    fi
  fi
fi
case_result offline_launch_plays_bag "${fail:+FAIL: $fail}"

# ---- demo.launch ----------------------------------------------------------------------------
fail=""
# Where its room server's client and its rviz config come from (resolved, not started).
args=$(inenv "roslaunch --args /room_server '$LAUNCH/demo.launch'" 2>>"$LOG")
echo "[install_space] demo.launch room_server: $args" >> "$LOG"
case "$args" in
  *"--static $DIST "*) ;;
  *) fail="demo.launch's room server is not given the installed client $DIST ($args); " ;;
esac
args=$(inenv "roslaunch --args /rviz '$LAUNCH/demo.launch' rviz:=true" 2>>"$LOG")
rviz_cfg=$(echo "$args" | sed -n 's/.*-d \([^ ]*\).*/\1/p')
echo "[install_space] demo.launch rviz: $args" >> "$LOG"
if [ -z "$rviz_cfg" ] || [ ! -f "$rviz_cfg" ] || [ "${rviz_cfg#"$INSTALL"/}" = "$rviz_cfg" ]; then
  fail="${fail}demo.launch's rviz config '$rviz_cfg' is not an installed file; "
fi
# A short session: 12 sets (10 empty), 4 cameras; the monitor ends the launch.
start=$(date +%s)
inenv "timeout 120 roslaunch -p $PORT '$LAUNCH/demo.launch' cameras:=$CAMERAS frames:=12 empty_frames:=10 monitor:=true cve_port:=$(free_port) output_dir:='$WORK/demo'" > "$WORK/demo.log" 2>&1
rc=$?
cat "$WORK/demo.log" >> "$LOG"
echo "[install_space] demo.launch: exit $rc after $(( $(date +%s) - start )) s" | tee -a "$LOG"
if [ $rc -eq 124 ]; then
  fail="${fail}demo.launch did not end after its frames (killed after 120 s); "
elif [ ! -f "$WORK/demo/summary.txt" ]; then
  fail="${fail}demo.launch (exit $rc) wrote no summary.txt; "
fi
if grep -q 'no browser client' "$WORK/demo.log" && [ -f "$DIST/index.html" ]; then
  fail="${fail}demo.launch's room server found no browser client; "
fi
if grep -q -E 'ResourceNotFound|cannot launch node|Failed to load nodelet|Could not find library' "$WORK/demo.log"; then
  fail="${fail}demo.launch could not start a node or nodelet from the install space; "
fi
case_result demo_launch_starts "${fail:+FAIL: $fail}"

finish
