#!/usr/bin/env bash
# Times the default plan (20 cm x 11 cm bar) from scratch and prints wall time, iterations,
# evaluations and the plan's figures; then re-verifies it with `overstep check`.
# Usage: tests/bench/plan_default.sh [BUILD_DIR] [extra `overstep plan` flags...]
set -euo pipefail
build=${1:-build}; shift || true
bin="$build/app/overstep"
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
start=$(date +%s.%N)
set +e
"$bin" plan --json --out "$out/plan.json" "$@" > "$out/summary.json" 2> "$out/progress.log"
code=$?
set -e
end=$(date +%s.%N)
python3 - "$out/summary.json" "$code" "$start" "$end" <<'PY'
import json, sys
s = json.load(open(sys.argv[1])) if open(sys.argv[1]).read().strip() else {}
wall = float(sys.argv[4]) - float(sys.argv[3])
print(f"exit {sys.argv[2]}  wall {wall:.1f} s  valid {s.get('valid')}  iterations {s.get('iterations')}  "
      f"evaluations {s.get('evaluations')}  solve {s.get('solve_time', 0):.1f} s")
if s:
    print(f"duration {s['duration']:.3f} s  phases {[round(d, 3) for d in s['phase_durations']]}  "
          f"step length {s['step_length']:.3f} m  foot spacing {s['foot_spacing']:.3f} m")
    t = s.get("time_split", {})
    print("split  " + "  ".join(f"{k} {v:.1f} s" for k, v in t.items()) +
          f"  ({s.get('jacobians')} Jacobians)")
PY
file=$(python3 -c "import json,sys; print(json.load(open('$out/summary.json')).get('file',''))" 2>/dev/null || true)
[ -n "$file" ] && [ -f "$file" ] && "$bin" check "$file" | tail -n 14 || true
