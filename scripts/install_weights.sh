#!/usr/bin/env bash
# Link kornia's pretrained local-feature weights from ../shared/weights into the torch hub cache
# (kornia looks there before downloading; nothing may be downloaded here). Skipped if absent.
set -euo pipefail
cd "$(dirname "$0")/.."
VENV=${VENV:-$PWD/.venv}
SHARED=${MATRIX_SHARED:-$PWD/../shared}
weights="$SHARED/weights"
if [ ! -d "$weights" ]; then
  echo "weights: $weights not found, skipping (registration backends that need weights will say so)"
  exit 0
fi
hub=$("$VENV/bin/python" -c 'import torch.hub; print(torch.hub.get_dir())')
mkdir -p "$hub/checkpoints"
for f in "$weights"/*.pth "$weights"/*.params "$weights"/*.pt "$weights"/extra/*.pth; do
  [ -f "$f" ] && ln -sf "$(readlink -f "$f")" "$hub/checkpoints/$(basename "$f")"
done
echo "weights: linked into $hub/checkpoints: $(ls "$hub/checkpoints" | tr '\n' ' ')"
