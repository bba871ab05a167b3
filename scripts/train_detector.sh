#!/usr/bin/env bash
# Train the default detector's recipe (bev/configs/detector.yaml) for the given seeds, one CPU thread each, all
# at once (two seeds fit the two cores of the reference machine), and export each seed's best-on-validation
# checkpoint with its training log next to it (a run stopped part way resumes from its last epoch, and its log goes
# on in the same file, so the seeds may be trained across working sessions):
#   matrix_core/bev/checkpoints/detector_seedN.pt, detector_seedN.log (per-epoch losses and validation),
#   detector_seedN.history.json.
# Usage: bash scripts/train_detector.sh 0 1   (data first: bash scripts/detector_data.sh)
# Another recipe of bev/configs by CONFIG: CONFIG=detector_tiny bash scripts/train_detector.sh 0 1 writes
# detector_tiny_seedN.* (the smaller, faster network: docs/detector.md).
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/env.sh
[ $# -ge 1 ] || { echo "usage: $0 SEED [SEED ...]" >&2; exit 2; }
ckpt=ros2_ws/src/matrix_core/matrix_core/bev/checkpoints
config=${CONFIG:-detector}
mkdir -p out/train   # the seeds' logs go beside their run folders, which train creates itself
pids=()
for seed in "$@"; do
  out="out/train/${config}_seed$seed"
  ( OMP_NUM_THREADS=1 PYTHONUNBUFFERED=1 matrix-tracker train --config "$config" --seed "$seed" --out "$out" --resume \
      --export-from best --export "$ckpt/${config}_seed$seed.pt" >> "$out.log" 2>> "$out.progress" \
    && cp "$out.log" "$ckpt/${config}_seed$seed.log" && cp "$out/history.json" "$ckpt/${config}_seed$seed.history.json" \
    && echo "seed $seed: done, $ckpt/${config}_seed$seed.pt" ) &
  pids+=($!)
  echo "seed $seed: training in the background; progress: tail -f $out.progress; log: $out.log"
done
status=0
for p in "${pids[@]}"; do wait "$p" || status=1; done
exit $status
