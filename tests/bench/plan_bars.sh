#!/usr/bin/env bash
# Plans the planner issue's eight bars from scratch, one after another (run it on an idle
# machine): the default 20 cm x 11 cm bar, the 5 cm bar, and the bar 5 mm lower / higher, nearer
# / farther and narrower / wider. One line per bar (exit code, wall time, validity, Jacobians,
# motion duration, objective, NLopt's and the derivatives' seconds), then the total. Exit 1 when
# a bar has no valid plan. The figures of docs/benchmarks.md's "Planning runs" come from it.
# Usage: tests/bench/plan_bars.sh [BUILD_DIR] [extra `overstep plan` flags...]
set -euo pipefail
build=${1:-build}; shift || true
bin="$build/app/overstep"
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
bars=("default:" "5cm:--obstacle-height 0.05"
      "height-0.195:--obstacle-height 0.195" "height-0.205:--obstacle-height 0.205"
      "gap-0.025:--obstacle-gap 0.025" "gap-0.035:--obstacle-gap 0.035"
      "width-0.105:--obstacle-width 0.105" "width-0.115:--obstacle-width 0.115")
failed=0
for bar in "${bars[@]}"; do
  name=${bar%%:*}
  read -r -a flags <<< "${bar#*:}"
  start=$(date +%s.%N)
  set +e
  "$bin" plan --json --time-limit 300 --out "$out/$name.json" "${flags[@]}" "$@" \
    > "$out/$name.summary.json" 2> "$out/$name.log"
  code=$?
  set -e
  end=$(date +%s.%N)
  python3 - "$name" "$code" "$start" "$end" "$out/$name.summary.json" <<'PY' || failed=1
import json, sys
name, code, start, end, path = sys.argv[1], int(sys.argv[2]), *map(float, sys.argv[3:5]), sys.argv[5]
text = open(path).read().strip()
s = json.loads(text) if text else {}
t = s.get("time_split", {})
print(f"{name:13s} exit {code}  {end - start:6.1f} s  valid {s.get('valid')}  "
      f"Jacobians {s.get('jacobians')}  duration {s.get('duration', float('nan')):.3f} s  "
      f"objective {s.get('objective', float('nan')):.3f}  NLopt {t.get('nlopt', float('nan')):.1f} s  "
      f"derivatives {t.get('derivatives', float('nan')):.1f} s", flush=True)
sys.exit(0 if code == 0 and s.get("valid") else 1)
PY
  echo "$start $end" >> "$out/times"
done
python3 - "$out/times" <<'PY'
import sys
total = sum(float(b) - float(a) for a, b in (line.split() for line in open(sys.argv[1])))
print(f"all eight: {total:.1f} s")
PY
exit "$failed"
