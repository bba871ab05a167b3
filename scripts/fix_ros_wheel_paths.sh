#!/usr/bin/env bash
# The ROS 2 interface wheels on PyPI were built in a manylinux image; their exported CMake targets name
# that image's Python and numpy include folders (/opt/python/cp311-cp311/...), which do not exist here.
# Building a rosidl interface package (matrix_msgs) needs them, so point those CMake files at this venv's
# own Python headers and numpy. Touches only files inside the venv; idempotent.
set -euo pipefail
VENV=${VENV:?VENV must name the virtual environment}
py_inc=$("$VENV/bin/python" -c 'import sysconfig; print(sysconfig.get_paths()["include"])')
np_inc=$("$VENV/bin/python" -c 'import numpy; print(numpy.get_include())')
if [ ! -f "$py_inc/Python.h" ]; then
  echo "fix_ros_wheel_paths: Python headers not found at $py_inc (install python3-dev)" >&2
  exit 1
fi
{ grep -rlZ "/opt/python/cp311-cp311" "$VENV/share" --include='*.cmake' 2>/dev/null || true; } \
  | xargs -0 -r sed -i \
      -e "s#/opt/python/cp311-cp311/lib/python3.11/site-packages/numpy/_core/include#$np_inc#g" \
      -e "s#/opt/python/cp311-cp311/include/python3.11#$py_inc#g"
