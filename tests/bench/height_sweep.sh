#!/usr/bin/env bash
# Finds the highest bar (width 11 cm) with a valid plan that `overstep check` accepts, scanning
# heights upward. Usage: tests/bench/height_sweep.sh [BUILD_DIR] [START] [STOP] [STEP]
set -euo pipefail
build=${1:-build}; start=${2:-0.05}; stop=${3:-0.40}; step=${4:-0.05}
bin="$build/app/overstep"
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
best=none
for h in $(python3 -c "import numpy as np; print(' '.join(f'{x:.3f}' for x in np.arange($start, $stop + 1e-9, $step)))"); do
  t0=$(date +%s.%N)
  if "$bin" plan --obstacle-height "$h" --out "$out/p.json" > /dev/null 2>&1 && "$bin" check "$out/p.json" > /dev/null 2>&1; then
    verdict=valid; best=$h
  else
    verdict=invalid
  fi
  printf "height %s m: %s (%.0f s)\n" "$h" "$verdict" "$(python3 -c "print($(date +%s.%N) - $t0)")"
done
echo "highest valid bar: $best m"
