# Sourced by the scripts: Debian's python3 first, the workspace's devel space, and a private
# ROS master port so that runs never meet another run's master.
export PATH=/usr/bin:/bin:$PATH
# A TCP port free on the loopback now, below the kernel's ephemeral range (free_port.py: why).
free_port() {
  /usr/bin/python3 "$ROOT/scripts/free_port.py"
}
set +u
# shellcheck disable=SC1091
source "$ROOT/devel/setup.bash"
if [ -z "${TABLETOP_KEEP_MASTER:-}" ]; then
  ROS_PORT=$(free_port)
  export ROS_PORT ROS_MASTER_URI="http://127.0.0.1:$ROS_PORT" ROS_HOSTNAME=127.0.0.1
fi
