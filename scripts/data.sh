#!/usr/bin/env bash
# `make data`: find the data this project needs, or fetch what can be fetched, or say what to put where.
#   1. $MATRIX_SHARED (default ../shared beside the repository) holds matrix_sample, multiviewx_sample,
#      weights, ros2_cli: say which are there; check matrix_sample against scripts/matrix_sample.sha256.
#   2. matrix_sample missing: clone the public MATRIX repository ($MATRIX_REPO_URL, bounded timeouts),
#      copy its sample into $MATRIX_SHARED/matrix_sample and verify the checksums; its images stay PNG
#      (the readers take .png and .jpg; our copy's JPEGs are only presence-checked there).
#   3. otherwise fail with exactly what to put where.
# `scripts/data.sh --require a,b` (make test, make demo): check only, no download; fail early, same message.
set -uo pipefail
ROOT="$(cd "$(dirname "$0")/.." && pwd)"
SHARED=${MATRIX_SHARED:-$ROOT/../shared}
MANIFEST=$ROOT/scripts/matrix_sample.sha256
REPO_URL=${MATRIX_REPO_URL:-https://github.com/KostaDakic/MATRIX.git}
NET_TIMEOUT=${MATRIX_NET_TIMEOUT:-20}       # seconds to reach the repository
CLONE_TIMEOUT=${MATRIX_CLONE_TIMEOUT:-900}  # seconds for the whole clone
PY=$(command -v python3 || command -v python)

declare -A USE=(
  [matrix_sample]="the real MATRIX sample: make demo, most tests (required)"
  [multiviewx_sample]="real MultiviewX files: tests/data_layer/test_multiviewx_sample.py (required by make test)"
  [weights]="kornia local-feature weights: make setup links them (optional: backends needing them say so)"
  [ros2_cli]="ROS 2 Jazzy CLI/launch sources: make setup builds ros2 when no ROS install gives it (optional)"
)
ORDER=(matrix_sample multiviewx_sample weights ros2_cli)

instructions() {
  cat >&2 <<EOF
data: missing: $*
Put the data here (or set MATRIX_SHARED=/some/folder that holds these folders):
  $SHARED/matrix_sample/       the MATRIX sample: image_subsets/D1..D8/0000..0004.{jpg,png}, calibrations/,
                               annotations_positions/, matchings/, reference/ (the layout of the public
                               repository $REPO_URL; \`make data\` fetches it when the network allows;
                               checksums: scripts/matrix_sample.sha256)
  $SHARED/multiviewx_sample/   MultiviewX files: Image_subsets/, annotations_positions/, calibrations/
                               (a few frames of the public MultiviewX dataset)
  $SHARED/weights/             optional: kornia weights (AffNet.pth, OriNet.pth, keynet_pytorch.pth, ...)
  $SHARED/ros2_cli/src/        optional: ROS 2 Jazzy ros2cli/launch sources (not needed with a ROS install)
Then run \`make data\` again to check.
EOF
}

report() {   # report: one line per expected folder; sets MISSING
  MISSING=()
  echo "data: MATRIX_SHARED=$SHARED"
  local d
  for d in "${ORDER[@]}"; do
    if [ -d "$SHARED/$d" ]; then echo "  found    $d/  (${USE[$d]})"
    else echo "  missing  $d/  (${USE[$d]})"; MISSING+=("$d"); fi
  done
}

verify() {   # verify DIR [--upstream]
  echo "data: checking $1 against $(basename "$MANIFEST")"
  if "$PY" "$ROOT/scripts/data_manifest.py" check "$1" "$MANIFEST" "${@:2}"; then echo "  checksums ok"
  else echo "data: $1 does not match $MANIFEST (files listed above)" >&2; return 1; fi
}

download() {   # download: the public sample into $SHARED/matrix_sample; non-zero with a reason when impossible
  command -v git >/dev/null || { echo "data: no git command: cannot download" >&2; return 1; }
  echo "data: trying $REPO_URL (at most ${NET_TIMEOUT} s to reach it)"
  if ! GIT_TERMINAL_PROMPT=0 timeout "$NET_TIMEOUT" git ls-remote --heads "$REPO_URL" >/dev/null 2>&1; then
    echo "data: cannot reach $REPO_URL (no network?): download impossible" >&2; return 1
  fi
  local tmp; tmp=$(mktemp -d); trap 'rm -rf "$tmp"' RETURN
  if ! GIT_TERMINAL_PROMPT=0 timeout "$CLONE_TIMEOUT" git clone --depth 1 -q "$REPO_URL" "$tmp/repo"; then
    echo "data: cloning $REPO_URL failed or took over ${CLONE_TIMEOUT} s" >&2; return 1
  fi
  local src; src=$(find "$tmp/repo" -type d -name annotations_positions -print -quit)
  if [ -z "$src" ] || [ ! -d "$(dirname "$src")/calibrations" ]; then
    echo "data: no MATRIX sample (annotations_positions/ beside calibrations/) in $REPO_URL" >&2; return 1
  fi
  src=$(dirname "$src")
  "$PY" "$ROOT/scripts/data_manifest.py" check "$src" "$MANIFEST" --upstream \
    || { echo "data: the repository's sample does not match $MANIFEST: not installed" >&2; return 1; }
  mkdir -p "$SHARED" && cp -r "$src" "$SHARED/matrix_sample.part" && mv "$SHARED/matrix_sample.part" "$SHARED/matrix_sample" \
    || { echo "data: cannot write $SHARED/matrix_sample" >&2; return 1; }
  echo "data: installed the public MATRIX sample at $SHARED/matrix_sample (checksums ok; PNG images)"
}

is_upstream_copy() { [ ! -f "$SHARED/matrix_sample/README.md" ]; }   # our copy has its README, upstream none

if [ "${1:-}" = "--require" ]; then   # make test / make demo: check only
  IFS=, read -r -a need <<< "${2:?--require needs a comma-separated list}"
  report >/dev/null
  absent=()
  for d in "${need[@]}"; do [[ " ${MISSING[*]} " == *" $d "* ]] && absent+=("$d"); done
  [ ${#absent[@]} -eq 0 ] || { instructions "${absent[@]}"; exit 2; }
  exit 0
fi

report
if [[ " ${MISSING[*]} " == *" matrix_sample "* ]]; then
  download || { instructions "${MISSING[@]}"; exit 2; }
  report
fi
if is_upstream_copy; then verify "$SHARED/matrix_sample" --upstream || exit 1
else verify "$SHARED/matrix_sample" || exit 1; fi
if [[ " ${MISSING[*]} " == *" multiviewx_sample "* ]]; then instructions "${MISSING[@]}"; exit 2; fi
echo "data: ready${MISSING[*]:+ (optional, absent: ${MISSING[*]})}"
