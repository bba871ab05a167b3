#!/usr/bin/env bash
# `make demo`: the whole live graph - bag_player -> calib + register (8 drones) -> fuse -> recorder, with the
# graph monitor - as separate processes over DDS in lockstep, on two recorded sequences:
#   1. the real MATRIX sample (turned into a rosbag2), 5 frames x 8 drones at 1920x1080;
#   2. a seeded simulated complex-variant sequence at 1920x1080 (the paper's size), DEMO_FRAMES frames.
# For each: calibration/registration errors (monitor), detection/tracking metrics of the live recording
# against the bag's ground truth, a picture of the tracks; for the simulated sequence also the same
# checkpoint offline on the same registration homographies (live and offline must agree).
# Run inside scripts/env.sh (the Makefile does). The graph runs as users run it,
#   ros2 launch matrix_bringup full_graph.launch.py bag:=BAG dataset:=DIR record:=... monitor:=true
# (a ROS install's ros2, or the one `make setup` builds here); without a ros2 command, through run_graph.
set -euo pipefail
cd "$(dirname "$0")/.."
SAMPLE=${SAMPLE:-$MATRIX_SHARED/matrix_sample}
OUT=${OUT:-out/demo}
FRAMES=${DEMO_FRAMES:-12}
DEFAULT_CHECKPOINT=$(python -c "from matrix_core.fusion.settings import shipped_checkpoint; print(shipped_checkpoint())")
RUN_GRAPH=ros2_ws/install/matrix_bringup/lib/matrix_bringup/run_graph   # where there is no ros2 command
[ -d "$SAMPLE" ] || { echo "demo: MATRIX sample not found at $SAMPLE (set SAMPLE=...)" >&2; exit 1; }
mkdir -p "$OUT"

live_graph() {  # live_graph NAME BAG DATASET [ARG:=VALUE...]: the graph, then the scores of what it published
  local name=$1 bag=$2 dataset=$3; shift 3
  rm -rf "${OUT:?}/$name"
  mkdir -p "$OUT/$name/logs"
  local live=()   # the live view (docs/live-view.md) where its port is free; DEMO_LIVE_VIEW=false: never
  if [ "${DEMO_LIVE_VIEW:-true}" != false ] && python -c "import socket; socket.create_server(('', 8765)).close()" 2>/dev/null; then
    live=(live_view:=true)
    echo "   live view: open ws://localhost:8765 in Foxglove or Lichtblick (layout: ros2_ws/src/matrix_live_view/config/foxglove_layout.json)"
  fi
  local args=(bag:="$bag" dataset:="$dataset" drones_per_process:=4 monitor:=true monitor_out:="$OUT/$name"
              record:="$OUT/$name/recording" overlay:=true "${live[@]}" "$@")
  if command -v ros2 >/dev/null 2>&1; then   # the path users take; it ends by itself after the bag
    echo "== $name: live graph (ROS_DOMAIN_ID=$ROS_DOMAIN_ID): ros2 launch matrix_bringup full_graph.launch.py ${args[*]}"
    if ! ROS_LOG_DIR="$OUT/$name/logs" ros2 launch matrix_bringup full_graph.launch.py "${args[@]}" \
        > "$OUT/$name/logs/launch.log" 2>&1; then
      tail -n 40 "$OUT/$name/logs/launch.log" >&2
      echo "demo: ros2 launch failed (all of its output: $OUT/$name/logs/launch.log)" >&2
      return 1
    fi
    grep -o "replay done: .*" "$OUT/$name/logs/launch.log" | sed 's/^/launch: /'
  else   # no ros2 CLI: the same processes through run_graph, flags of the same names
    local flags=() arg
    for arg in "${args[@]}"; do flags+=("--${arg%%:=*}" "${arg#*:=}"); done
    echo "== $name: live graph (ROS_DOMAIN_ID=$ROS_DOMAIN_ID): run_graph ${flags[*]}"
    "$RUN_GRAPH" "${flags[@]}" --log_dir "$OUT/$name/logs"
  fi
  echo "-- $name: calibration (calib) and registration (register) published live, against the ground truth"
  cat "$OUT/$name/graph_summary.txt"
  echo "-- $name: detections and tracks published live (fuse), against the bag's ground truth"
  echo "   and in the image plane: every drone's detections_2d (fused ids) against the annotated boxes"
  matrix-tracker evaluate-recording "$OUT/$name/recording" --ground-truth "$bag" \
    --json "$OUT/$name/live_metrics.json" --png "$OUT/$name/tracks.png" --dataset "$dataset" \
    --png-2d "$OUT/$name/boxes_2d.png" --boxes-2d "$OUT/$name/boxes_2d.txt" --overlays "$OUT/$name/overlays"
}

echo "== dataset"
matrix-tracker info "$SAMPLE"
BAG=$OUT/matrix_sample_bag
if [ ! -f "$BAG/metadata.yaml" ]; then
  echo "== bag: $SAMPLE -> $BAG"
  rm -rf "$BAG"
  matrix-tracker bag "$SAMPLE" --out "$BAG"   # raw Image: exactly the sample's pixels (a JPEG of its JPEGs moves poses)
fi
live_graph real "$BAG" "$SAMPLE"

echo "== simulator: a seeded complex-variant sequence ($FRAMES frames x 8 drones, 1920x1080) and its bag"
SIM=$OUT/sim
rm -rf "$SIM"
matrix-tracker simulate --config complex --frames "$FRAMES" --seed 7 --image_ext .jpg --bag --compressed --out "$SIM"
matrix-tracker info "$SIM" | grep -E "^(format|views|frames|people|camera_height_m)"
# the same default checkpoint as on the real sample (docs/detector.md)
live_graph simulated "$SIM/bag" "$SIM"

echo "== simulated: the same checkpoint offline on the same frames, with the registration homographies"
matrix-tracker register "$SIM" --out "$OUT/simulated/offline_registration" > "$OUT/simulated/offline_register.log" 2>&1
matrix-tracker evaluate "$SIM" --checkpoint "$DEFAULT_CHECKPOINT" --calibration registration \
  --calibration-dir "$OUT/simulated/offline_registration" --out "$OUT/simulated/offline" --heatmaps 2
python - "$OUT/simulated" <<'EOF'
import json, sys
from pathlib import Path
d = Path(sys.argv[1])
live, off = (json.loads((d / f).read_text()) for f in ('live_metrics.json', 'offline/metrics.json'))
print(f'{"":>8} {"MODA":>7} {"MOTA":>7} {"IDF1":>7}   2D: {"prec":>6} {"rec":>6} {"MOTA":>6} {"IDF1":>6}')
for name, m, m2 in (('live', live, live['image_plane']['per_drone']['all']), ('offline', off, off['image_plane']['all'])):
    print(f'{name:>8} {100 * m["detection"]["moda"]:7.2f} {100 * m["tracking"]["mota"]:7.2f} {100 * m["tracking"]["idf1"]:7.2f}'
          f'       ' + ' '.join(f'{100 * m2[k]:6.2f}' for k in ('precision', 'recall', 'mota', 'idf1')))
EOF
echo "pictures: $OUT/real/graph_overview.png, $OUT/real/tracks.png, $OUT/simulated/tracks.png," \
     "$OUT/simulated/offline/trajectories.png; image plane: $OUT/{real,simulated}/boxes_2d.png and the" \
     "overlays fuse published, $OUT/{real,simulated}/overlays/overlay_D*.png; node logs: $OUT/{real,simulated}/logs/"
