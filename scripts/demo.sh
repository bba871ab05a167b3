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
cleanup   # this graph is done; the next one starts its own nodes
echo "logs: $OUT/{calib,register,player,monitor}.log"

echo "== simulator: a seeded complex-variant sequence (10 frames x 8 drones, 640x360) with its bag"
rm -rf "$OUT/sim"
matrix-tracker simulate --config complex --frames 10 --seed 7 --fast --image_ext .jpg --bag --out "$OUT/sim"
matrix-tracker info "$OUT/sim" | grep -E "^(format|views|frames|people|camera_height_m)"

CKPT=$(python -c 'from matrix_core.fusion.settings import shipped_checkpoint; print(shipped_checkpoint())')
echo "== live graph on it: bag_player -> fuse (BEV network + tracker, the bag's per-frame CameraInfo) -> recorder, lockstep on /tracks"
rm -rf "$OUT/live"; mkdir -p "$OUT/live"
pids=()
start matrix_bev_tracker fuse live/fuse.log --ros-args -p input_kind:=camera_info -p use_sim_time:=true \
  -p 'camera_info_topic:=/{view}/ground_truth/camera_info' \
  -p sync_timeout:=30.0 -p "checkpoint:=$CKPT"
start matrix_ros recorder live/recorder.log --ros-args -p "out:=$OUT/live/recording" -p use_sim_time:=true \
  -p 'topics:=[/tracks,/detections,/bev_heatmap]' \
  -p 'types:=[matrix_msgs/msg/TrackArray,matrix_msgs/msg/TrackArray,nav_msgs/msg/OccupancyGrid]' \
  -p tracks_topic:=/tracks -p "mot_file:=$OUT/live/tracks.txt"
sleep 8   # DDS discovery: fuse -> recorder must be matched before frame 0 leaves the bag
"$INSTALL/matrix_ros/lib/matrix_ros/bag_player" --ros-args -p "bag:=$OUT/sim/bag" -p wait_for_subscribers:=1 \
  -p 'topics:=[/D1/image_raw,/D2/image_raw,/D3/image_raw,/D4/image_raw,/D5/image_raw,/D6/image_raw,/D7/image_raw,/D8/image_raw,/D1/ground_truth/camera_info,/D2/ground_truth/camera_info,/D3/ground_truth/camera_info,/D4/ground_truth/camera_info,/D5/ground_truth/camera_info,/D6/ground_truth/camera_info,/D7/ground_truth/camera_info,/D8/ground_truth/camera_info]' \
  -p lockstep:=true -p lockstep_topic:=/tracks -p lockstep_type:=matrix_msgs/msg/TrackArray -p lockstep_timeout:=60.0 \
  > "$OUT/live/player.log" 2>&1
sleep 1
cleanup
grep -h "played\|published" "$OUT/live/player.log" "$OUT/live/fuse.log" | tail -n 2
echo "== scores of the live recording (tracks and detections published by fuse) against the bag's ground truth"
matrix-tracker evaluate-recording "$OUT/live/recording" --ground-truth "$OUT/sim/bag" --json "$OUT/live/metrics.json"

echo "== the same checkpoint offline on the same frames (ground-truth calibration), with pictures"
matrix-tracker evaluate "$OUT/sim" --checkpoint "$CKPT" --out "$OUT/bev" --heatmaps 2
echo "logs: $OUT/live/*.log; pictures: $OUT/graph_overview.png, $OUT/bev/trajectories.png, $OUT/bev/heatmap_*.png"
