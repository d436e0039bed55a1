#!/usr/bin/env bash
# Loop timing of `overstep replay` on this machine: a 60 s standing plan replayed with the timer
# clock against `overstep sim --realtime`, at 200 Hz and at 1 kHz, inside a private network
# namespace (needs root). Prints the period statistics over the run, overruns, missed cycles and
# the round trip (command sent -> robot state reporting it).
# Usage: tests/bench/replay_timing.sh [BUILD_DIR] [SECONDS]
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
build=${1:-build}
seconds=${2:-60}
bin=$(realpath "$build/app/overstep")
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
"$bin" plan --stand "$seconds" --out "$out/stand.json" 2>/dev/null
cat > "$out/run.sh" <<RUN
#!/usr/bin/env bash
set -u
for rate in 200 1000; do
  "$bin" sim --realtime --no-obstacle --rate \$rate > /dev/null 2> "$out/sim.err" &
  sim=\$!
  # The watchdog in wall time: 15 ms (3 periods at 200 Hz, 15 at 1 kHz, where 3 ms is shorter
  # than this VM's scheduling hiccups: a 3-period watchdog tripped after 2 s, measured).
  wd=\$(( rate == 1000 ? 15 : 3 ))
  "$bin" replay "$out/stand.json" --clock timer --rate \$rate --watchdog \$wd --start --json --quiet --linger 0.1 \
    > "$out/replay_\$rate.json" 2> "$out/replay.err"
  kill \$sim; wait \$sim 2>/dev/null
done
RUN
chmod +x "$out/run.sh"
"$here/../integration/netns_run.sh" "$out/run.sh"
for rate in 200 1000; do
  python3 - "$out/replay_$rate.json" "$rate" <<'PY'
import json, sys
j = json.load(open(sys.argv[1]))
p, q, r = j["period_us"], j["processing_us"], j["round_trip_us"]
print(f"{sys.argv[2]:>5} Hz  state {j['state']}{(' (' + j['fault'] + ')') if j['fault'] else ''}  ticks {j['ticks']:>6}  period us: min {p['min']:.0f} "
      f"mean {p['mean']:.1f} p99 {p['p99']:.0f} max {p['max']:.0f}  processing us: mean "
      f"{q['mean']:.1f} max {q['max']:.0f}  overruns {j['overruns']}  missed {j['missed_cycles']}  "
      f"round trip us: mean {r['mean']:.0f} max {r['max']:.0f}  ({j['realtime']})")
PY
done
