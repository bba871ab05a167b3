#!/usr/bin/env bash
# The `ros2` command line and `launch` (ros2 run | launch | topic | node | param | interface) for the pip
# environment, which has rclpy but neither: built from the Jazzy sources in $MATRIX_SHARED/ros2_cli into
# ros2_ws/cli_overlay/{build,install}; scripts/env.sh puts it on the paths. Skipped where a `ros2` command
# already exists (a real ROS 2 install has its own) and when already built. No --symlink-install: the
# sources are read-only in CI (a symlink build writes *.egg-info beside them).
set -euo pipefail
cd "$(dirname "$0")/.."
ROOT=$PWD
VENV=${VENV:-$ROOT/.venv}
SRC=${MATRIX_SHARED:-$ROOT/../shared}/ros2_cli/src
OVERLAY=$ROOT/ros2_ws/cli_overlay
if [ -f "$OVERLAY/install/ros2cli/bin/ros2" ]; then
  exit 0
fi
if command -v ros2 >/dev/null 2>&1; then
  echo "build_cli: using the installed $(command -v ros2)"
  exit 0
fi
if [ ! -d "$SRC" ]; then
  echo "build_cli: no ros2 command and no sources at $SRC: ros2 run / launch will not be available" >&2
  exit 0
fi
export PATH="$VENV/bin:$PATH" AMENT_PREFIX_PATH="$VENV" CMAKE_PREFIX_PATH="$VENV"
echo "build_cli: building ros2 CLI and launch from $SRC"
mkdir -p "$OVERLAY"
cd "$OVERLAY"
colcon --log-base log build --base-paths "$SRC" --build-base build --install-base install \
  --cmake-args -DBUILD_TESTING=OFF \
  --event-handlers console_direct- console_cohesion- console_stderr- summary+ status- 2>&1 | grep -v "had stderr output" | tail -n 3
test -f install/ros2cli/bin/ros2
