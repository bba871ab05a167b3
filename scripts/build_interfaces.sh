#!/usr/bin/env bash
# The standard interface packages that the package index lacks, vision_msgs and tf2_msgs, built from the
# upstream sources in $MATRIX_SHARED/ros2_interfaces into ros2_ws/interfaces_overlay/{build,install};
# scripts/env.sh puts it on the paths. Skipped where an installed ROS 2 (a prefix of the caller's
# AMENT_PREFIX_PATH, given as CALLER_AMENT_PREFIX_PATH by scripts/build.sh) already has both, and when
# already built. No --symlink-install: the sources are read-only in CI.
set -euo pipefail
cd "$(dirname "$0")/.."
ROOT=$PWD
VENV=${VENV:-$ROOT/.venv}
SRC=${MATRIX_SHARED:-$ROOT/../shared}/ros2_interfaces/src
OVERLAY=$ROOT/ros2_ws/interfaces_overlay
PACKAGES=(vision_msgs tf2_msgs)
if [ -f "$OVERLAY/install/vision_msgs/share/vision_msgs/package.xml" ] \
  && [ -f "$OVERLAY/install/tf2_msgs/share/tf2_msgs/package.xml" ]; then
  exit 0
fi
installed() {  # a prefix outside this checkout that has the package
  local prefix
  IFS=: read -r -a prefixes <<< "${CALLER_AMENT_PREFIX_PATH:-${AMENT_PREFIX_PATH:-}}"
  for prefix in "${prefixes[@]}"; do
    [ -n "$prefix" ] && [ "$prefix" != "$VENV" ] && [[ "$prefix" != "$ROOT"/* ]] \
      && [ -f "$prefix/share/$1/package.xml" ] && return 0
  done
  return 1
}
if installed vision_msgs && installed tf2_msgs; then
  echo "build_interfaces: using the installed vision_msgs and tf2_msgs"
  exit 0
fi
if [ ! -d "$SRC" ]; then
  echo "build_interfaces: no sources at $SRC: no vision_msgs / tf2_msgs outputs, no live view" >&2
  exit 0
fi
export PATH="$VENV/bin:$PATH" AMENT_PREFIX_PATH="$VENV" CMAKE_PREFIX_PATH="$VENV"
echo "build_interfaces: building ${PACKAGES[*]} from $SRC (about a minute)"
mkdir -p "$OVERLAY"
cd "$OVERLAY"
colcon --log-base log build --base-paths "$SRC" --packages-select "${PACKAGES[@]}" --build-base build \
  --install-base install --cmake-args -DBUILD_TESTING=OFF \
  --event-handlers console_direct- console_cohesion- console_stderr- summary+ status- 2>&1 | grep -v "had stderr output" | tail -n 3
test -f install/vision_msgs/share/vision_msgs/package.xml && test -f install/tf2_msgs/share/tf2_msgs/package.xml
