#!/usr/bin/env bash
# `make demo`: turn the real MATRIX sample into a rosbag2 and replay it through the ROS 2 graph (separate processes over DDS),
# print the scores and write pictures to out/demo/. Run inside scripts/env.sh (the Makefile does).
# The same graph on a full ROS 2 install: ros2 launch matrix_bringup calib_register.launch.py dataset:=...
set -euo pipefail
cd "$(dirname "$0")/.."
SAMPLE=${SAMPLE:-$MATRIX_SHARED/matrix_sample}
OUT=${OUT:-out/demo}
INSTALL=ros2_ws/install
VIEWS='[D1,D2,D3,D4,D5,D6,D7,D8]'
mkdir -p "$OUT"
[ -d "$SAMPLE" ] || { echo "demo: MATRIX sample not found at $SAMPLE (set SAMPLE=...)" >&2; exit 1; }

echo "== dataset"
matrix-tracker info "$SAMPLE"

pids=()
cleanup() {  # SIGTERM every node, then SIGKILL what is still there after 10 s: no orphans
  for p in "${pids[@]}"; do kill "$p" 2>/dev/null || true; done
  for _ in $(seq 100); do
    alive=0; for p in "${pids[@]}"; do kill -0 "$p" 2>/dev/null && alive=1; done
    [ $alive = 0 ] && break; sleep 0.1
  done
  for p in "${pids[@]}"; do kill -9 "$p" 2>/dev/null || true; done
  wait 2>/dev/null || true
}
trap cleanup EXIT INT TERM
start() {  # start PACKAGE EXECUTABLE LOG ARGS...: a node in its own process, logging to OUT/LOG
  local pkg=$1 exe=$2 log=$3; shift 3
  "$INSTALL/$pkg/lib/$pkg/$exe" "$@" > "$OUT/$log" 2>&1 &
  pids+=($!)
}

BAG=$OUT/matrix_sample_bag
if [ ! -f "$BAG/metadata.yaml" ]; then
  echo "== bag: $SAMPLE -> $BAG"
  rm -rf "$BAG"
  matrix-tracker bag "$SAMPLE" --out "$BAG"
fi

echo "== graph: bag_player -> calib (8 drones) + register (8 drones) -> graph_monitor (ROS_DOMAIN_ID=$ROS_DOMAIN_ID)"
start matrix_calib calib calib.log --ros-args -p "views:=$VIEWS" -p "prior_dataset:=$SAMPLE" -p qos:=reliable
start matrix_register register register.log --ros-args -p "views:=$VIEWS" -p "reference_dataset:=$SAMPLE"
frames=$(matrix-tracker info "$SAMPLE" --json | python -c 'import json,sys; print(json.load(sys.stdin)["frames"])')
"$INSTALL/matrix_bringup/lib/matrix_bringup/graph_monitor" --ros-args -p "views:=$VIEWS" \
  -p "expected_frames:=$frames" -p idle_timeout:=120.0 -p "out_dir:=$OUT" 2> "$OUT/monitor.log" &
monitor=$!
# DDS discovery of the result topics (homography, camera_info) takes a moment; the player itself
# waits until every image topic has its three subscribers.
sleep 5
# Lockstep: the next frame leaves the bag only when the monitor saw every drone's homography of the last.
start matrix_ros bag_player player.log --ros-args -p "bag:=$BAG" -p wait_for_subscribers:=3 \
  -p lockstep:=true -p lockstep_topic:=/graph_monitor/frame_done -p lockstep_type:=std_msgs/msg/Header
wait "$monitor"
echo "logs: $OUT/{calib,register,player,monitor}.log"

echo "== simulator: a seeded complex-variant sequence (10 frames x 8 drones, 640x360) with its bag"
rm -rf "$OUT/sim"
matrix-tracker simulate --config complex --frames 10 --seed 7 --fast --image_ext .jpg --bag --out "$OUT/sim"
matrix-tracker info "$OUT/sim" | grep -E "^(format|views|frames|people|camera_height_m)"

echo "== BEV detection + tracking with the shipped checkpoint on that sequence (offline; the live fuse node is not built yet)"
CKPT=$(python -c 'import matrix_core.bev, pathlib; print(pathlib.Path(matrix_core.bev.__file__).parent / "checkpoints/complex_quick.pt")')
matrix-tracker evaluate "$OUT/sim" --checkpoint "$CKPT" --out "$OUT/bev" --heatmaps 2
echo "pictures: $OUT/graph_overview.png, $OUT/bev/trajectories.png, $OUT/bev/heatmap_*.png"
