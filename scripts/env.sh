# Source this: the environment the nodes, tools and tests run in (venv + built workspace + DDS isolation).
_root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
export VENV="${VENV:-$_root/.venv}"
export PATH="$VENV/bin:$PATH"
export AMENT_PREFIX_PATH="$VENV${AMENT_PREFIX_PATH:+:$AMENT_PREFIX_PATH}"
export CMAKE_PREFIX_PATH="$VENV${CMAKE_PREFIX_PATH:+:$CMAKE_PREFIX_PATH}"
# The ros2 CLI and launch built by scripts/build_cli.sh, unless a real ROS 2 install already gives `ros2`.
if [ -f "$_root/ros2_ws/cli_overlay/install/local_setup.sh" ] && ! command -v ros2 >/dev/null 2>&1; then
  set +u
  COLCON_CURRENT_PREFIX="$_root/ros2_ws/cli_overlay/install" . "$_root/ros2_ws/cli_overlay/install/local_setup.sh"
fi
# vision_msgs and tf2_msgs built by scripts/build_interfaces.sh where no installed ROS 2 has them.
if [ -f "$_root/ros2_ws/interfaces_overlay/install/local_setup.sh" ]; then
  set +u
  COLCON_CURRENT_PREFIX="$_root/ros2_ws/interfaces_overlay/install" . "$_root/ros2_ws/interfaces_overlay/install/local_setup.sh"
fi
if [ -f "$_root/ros2_ws/install/setup.sh" ]; then
  set +u
  COLCON_CURRENT_PREFIX="$_root/ros2_ws/install" . "$_root/ros2_ws/install/setup.sh"
fi
# Keep DDS traffic on this machine and away from other runs: tests and demos pick their own domain.
export ROS_AUTOMATIC_DISCOVERY_RANGE="${ROS_AUTOMATIC_DISCOVERY_RANGE:-LOCALHOST}"
export ROS_DOMAIN_ID="${ROS_DOMAIN_ID:-$(( (RANDOM % 90) + 5 ))}"
# Fast DDS defaults resend a lost fragment of a large image only after a 3 s heartbeat; this profile
# (bigger shared-memory segment, 0.1 s heartbeat) keeps 8 x 1080p frames flowing at 2 Hz.
export FASTRTPS_DEFAULT_PROFILES_FILE="${FASTRTPS_DEFAULT_PROFILES_FILE:-$_root/ros2_ws/src/matrix_bringup/config/fastdds.xml}"
export MATRIX_SHARED="${MATRIX_SHARED:-$_root/../shared}"
unset _root
