#!/usr/bin/env bash
# `make setup`: create .venv with pinned packages, build the ROS 2 workspace, install offline weights.
# Idempotent: re-running only redoes what changed.
set -euo pipefail
cd "$(dirname "$0")/.."
ROOT=$PWD
VENV=${VENV:-$ROOT/.venv}
PYTHON=${PYTHON:-python3}

if [ ! -x "$VENV/bin/python" ]; then
  echo "setup: creating $VENV"
  "$PYTHON" -m venv "$VENV"
fi

# Reinstall packages only when the requirement files change.
stamp="$VENV/.requirements.sha256"
want=$(cat requirements.txt requirements-nodeps.txt constraints.txt | sha256sum | cut -d' ' -f1)
if [ "$(cat "$stamp" 2>/dev/null)" != "$want" ]; then
  echo "setup: installing pinned packages (constraints.txt)"
  "$VENV/bin/pip" install --disable-pip-version-check -q -c constraints.txt -r requirements.txt
  # Packages whose declared dependencies clash with ours (requirements-nodeps.txt says why), pinned too.
  "$VENV/bin/pip" install --disable-pip-version-check -q --no-deps -c constraints.txt -r requirements-nodeps.txt
  echo "$want" > "$stamp"
fi

# The core package, editable, gives .venv/bin/matrix-tracker.
if [ ! -x "$VENV/bin/matrix-tracker" ]; then
  "$VENV/bin/pip" install --disable-pip-version-check -q --no-deps --no-build-isolation -e ros2_ws/src/matrix_core
fi

bash scripts/build.sh
bash scripts/install_weights.sh
echo "setup: done ($VENV)"
