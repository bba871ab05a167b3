#!/usr/bin/env bash
# colcon build of ros2_ws inside the venv (the ROS 2 Jazzy wheels from PyPI live in .venv).
set -euo pipefail
cd "$(dirname "$0")/.."
ROOT=$PWD
VENV=${VENV:-$ROOT/.venv}
export PATH="$VENV/bin:$PATH" VENV
# An installed ROS 2 (the caller's prefixes) may already have the standard interfaces build_interfaces.sh builds.
export CALLER_AMENT_PREFIX_PATH="${AMENT_PREFIX_PATH:-}"
# colcon and ament look for the ROS packages under these prefixes; the pip wheels install into the venv.
export AMENT_PREFIX_PATH="$VENV" CMAKE_PREFIX_PATH="$VENV"
bash scripts/fix_ros_wheel_paths.sh
bash scripts/build_cli.sh
bash scripts/build_interfaces.sh
cd ros2_ws
# A file removed from the sources leaves a dangling symlink in a --symlink-install build, which colcon then
# fails to copy: drop those, so that an existing checkout builds after a pull.
[ -d build ] && find build -xtype l -delete
colcon --log-base log build --symlink-install --base-paths src --build-base build --install-base install \
  --event-handlers console_direct- console_cohesion- summary+ status- 2>&1 | tail -n 5
