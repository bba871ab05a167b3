#!/usr/bin/env bash
# Simulate the sequences of the default detector's recipe (bev/configs/detector.yaml names the same commands):
# training (complex seeds 101-108 and modified seeds 121-124, 60 frames each: twelve randomised looks of the
# scene, lighting, floor, backdrop and distractors, which are drawn once per sequence), validation (111, 112), tracker validation (113, 114: longer sequences on which
# the tracker settings are chosen, scripts/tune_tracker.py) and held-out test (201, 202) sequences into data/.
# Complete folders are kept, partial ones regenerated. Usage: bash scripts/detector_data.sh [train|val|trackval|test ...]
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/env.sh
sets=("$@"); [ ${#sets[@]} -eq 0 ] && sets=(train val test)
sim() {  # variant frames seed name
  local out="data/det_$4"
  local last; last=$(printf '%04d' $(($2 - 1)))
  if [ -f "$out/annotations_positions/$last.json" ]; then echo "kept $out (complete)"; return; fi
  rm -rf "$out"
  matrix-tracker simulate --config "$1" --frames "$2" --seed "$3" --out "$out" --fast true --image_ext .jpg
}
for s in "${sets[@]}"; do
  case "$s" in
    train) for seed in 101 102 103 104 105 106 107 108; do sim complex 60 $seed complex_train_s$seed; done
           for seed in 121 122 123 124; do sim modified 60 $seed modified_train_s$seed; done ;;
    val)   sim complex 30 111 complex_val_s111; sim modified 30 112 modified_val_s112 ;;
    trackval) sim complex 60 113 complex_trackval_s113; sim modified 60 114 modified_trackval_s114 ;;
    test)  sim complex 60 201 complex_test_s201; sim modified 60 202 modified_test_s202 ;;
    *) echo "unknown set $s (train, val, trackval, test)" >&2; exit 2 ;;
  esac
done
