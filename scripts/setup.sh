#!/usr/bin/env bash
# Sets up a fresh Debian 12 machine for tabletop hands and builds the workspace.
#  - installs the Debian packages below if any is missing (needs root; apt only, no rosdep);
#  - builds the catkin workspace (this repository) in Release with Debian's python3;
#  - builds the browser client of the CVE room (src/cvephands_bridge/web -> web/dist) from the
#    npm registry's packages pinned in its package-lock.json (three.js, fzstd, esbuild,
#    playwright-core for the browser test, which drives Debian's chromium).
# Idempotent: with everything installed and nothing changed it takes a few seconds.
# Usage: scripts/setup.sh [--bench] [extra catkin_make args]
#   --bench  also install the peer libraries of the benchmarks (Open3D, for bench_carving)
set -eo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
BENCH_PACKAGES=()
if [ "${1:-}" = "--bench" ]; then
  BENCH_PACKAGES=(libopen3d-dev)
  shift
fi

# Exact Debian packages (bookworm). ROS 1 comes from Debian's archive.
PACKAGES=(
  build-essential cmake ccache pkg-config
  ros-base-dev ros-base-python-dev rosbash python3-rosbag python3-rostest python3-nose
  libnodeletlib-dev libimage-transport-dev libcv-bridge-dev libtf2-ros-dev
  libmessage-filters-dev librosbag-dev libdiagnostic-updater-dev libvisualization-msgs-dev
  libstd-srvs-dev libdynamic-reconfigure-config-init-mutex-dev python3-dynamic-reconfigure
  libpcl-dev libpcl-conversions-dev libopencv-dev libopencv-contrib-dev libeigen3-dev libyaml-cpp-dev
  libceres-dev
  libgtest-dev libbenchmark-dev libzstd-dev libboost-dev libssl-dev libhwy-dev nlohmann-json3-dev
  rviz xvfb x11-apps imagemagick libgl1-mesa-dri
  chromium
)
# Node.js and npm build the browser client; a machine that already has them (e.g. from
# NodeSource) keeps its own, Debian's are installed otherwise.
command -v npm >/dev/null 2>&1 || PACKAGES+=(nodejs npm)

missing=()
for p in "${PACKAGES[@]}" "${BENCH_PACKAGES[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "[setup] installing ${#missing[@]} Debian packages: ${missing[*]}"
  SUDO=""
  if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
  $SUDO apt-get update -q
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -q --no-install-recommends "${missing[@]}"
fi

# pyenv's python3 on PATH breaks catkin and pluginlib at configure time: use Debian's.
export PATH=/usr/bin:/bin:$PATH
export CCACHE_DIR="${CCACHE_DIR:-$HOME/.ccache}"
# Paths under the checkout's parent hash as relative ones, so that another clone with the same
# layout (CI's clean clone, ../shared beside it) reuses the cache instead of rebuilding.
export CCACHE_BASEDIR="${CCACHE_BASEDIR:-$(dirname "$ROOT")}"
cd "$ROOT"
echo "[setup] building workspace in $ROOT/build (Release)"
set +e
catkin_make -j2 -DCMAKE_BUILD_TYPE=Release \
  -DPYTHON_EXECUTABLE=/usr/bin/python3 -DPython3_EXECUTABLE=/usr/bin/python3 \
  -DCMAKE_CXX_COMPILER_LAUNCHER=ccache -DCATKIN_ENABLE_TESTING=ON "$@" 2>&1 |
  grep --line-buffered -v -E '^-- |^Base path|^Source space|^Build space|^Devel space|^Install space|^#### |^Scanning dependencies'
rc=${PIPESTATUS[0]}
set -e
if [ "$rc" -ne 0 ]; then echo "[setup] build FAILED (catkin_make exit $rc)"; exit "$rc"; fi

WEB="$ROOT/src/cvephands_bridge/web"
if [ ! -f "$WEB/node_modules/.package-lock.json" ] ||
   [ "$WEB/package-lock.json" -nt "$WEB/node_modules/.package-lock.json" ]; then
  echo "[setup] installing the browser client's npm packages (npm ci)"
  # Not fatal: without the client the pipeline, the room server (relaying only) and every
  # other test still work; the browser tests then skip, saying why.
  (cd "$WEB" && npm ci --no-audit --no-fund --loglevel=error) ||
    echo "[setup] WARNING: npm ci failed (no npm registry?): the browser client is not built"
fi
if [ ! -f "$WEB/dist/app.js" ] || [ -n "$(find "$WEB/src" "$WEB/index.html" "$WEB/style.css" \
     "$WEB/build.mjs" "$WEB/package-lock.json" -newer "$WEB/dist/app.js" 2>/dev/null | head -n 1)" ]; then
  if [ -f "$WEB/node_modules/.package-lock.json" ]; then
    (cd "$WEB" && node build.mjs) || echo "[setup] WARNING: building the browser client failed"
  fi
fi
echo "[setup] ok"
