#!/usr/bin/env bash
# Finds the highest bar (width 11 cm) with a valid plan that `overstep check` accepts. The first
# height is planned from scratch (or taken from START_PLAN, a valid plan for it); each next height
# is warm-started from the last valid plan (`overstep plan --warm-start`: a feasibility
# restoration, then only the target stage), the obstacle-height homotopy continued. Stops at the
# first height without a valid plan.
# Usage: [START_PLAN=plan.json] tests/bench/height_sweep.sh [BUILD_DIR] [START] [STOP] [STEP]
set -euo pipefail
build=${1:-build}; start=${2:-0.20}; stop=${3:-0.40}; step=${4:-0.025}
bin="$build/app/overstep"
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
best=none
prev=""
first=1
for h in $(python3 -c "print(' '.join(f'{$start + i * $step:.3f}' for i in range(int(round(($stop - $start) / $step)) + 1)))"); do
  t0=$(date +%s.%N)
  plan="$out/p$h.json"
  if [ "$first" = 1 ] && [ -n "${START_PLAN:-}" ]; then
    cp "$START_PLAN" "$plan"
    planned=0
  else
    args=(plan --obstacle-height "$h" --out "$plan" --json)
    [ -n "$prev" ] && args+=(--warm-start "$prev")
    "$bin" "${args[@]}" > "$out/s$h.json" 2> /dev/null && planned=0 || planned=$?
  fi
  first=0
  verdict="invalid (plan exit $planned)"
  if [ "$planned" = 0 ] && "$bin" check "$plan" > /dev/null 2>&1; then
    verdict=valid; best=$h; prev="$plan"
  fi
  dur=$(python3 -c "import json; print(round(json.load(open('$plan'))['summary']['duration'], 3))" 2>/dev/null || echo "-")
  printf "height %s m: %s, duration %s s (%.0f s)\n" "$h" "$verdict" "$dur" \
    "$(python3 -c "print($(date +%s.%N) - $t0)")"
  [ "$verdict" = valid ] || break
done
echo "highest valid bar: $best m"
