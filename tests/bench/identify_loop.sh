#!/usr/bin/env bash
# The identification loop on the default obstacle (issue 8): `overstep demo --truth payload.yaml
# --identify` for each seed (the simulator's sensor noise; the experiment and the second run use
# SEED + 1 and SEED + 2), then one line per seed: the identified payload, joint tracking RMS and
# stabilizer effort before (the plan for the base model) and after (the warm re-plan for the
# identified overlay), and the same plan run without the payload as the reference.
# The truth: 1.5 kg on CHEST_LINK1 at (0.05, 0, 0.10) m (override with TRUTH=file.yaml).
# START_PLAN=plan.json (a valid default plan) skips the ~2.5 min of planning the first run needs
# (`--plan`: the run before is that plan, and the re-plan starts from it).
# Needs root (a private network namespace for LCM, tests/integration/netns_run.sh).
# Usage: [START_PLAN=plan.json] [TRUTH=truth.yaml] tests/bench/identify_loop.sh [BUILD_DIR] [SEED...]
set -euo pipefail
build=${1:-build}
shift || true
seeds=("$@")
[ ${#seeds[@]} -gt 0 ] || seeds=(1 2 3)
here=$(cd "$(dirname "$0")/../.." && pwd)
bin=$(cd "$build" && pwd)/app/overstep
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
truth=${TRUTH:-$out/payload.yaml}
[ -n "${TRUTH:-}" ] ||
  printf 'payload:\n  - {link: CHEST_LINK1, mass: 1.5, offset: [0.05, 0.0, 0.10]}\n' > "$truth"
netns="$here/tests/integration/netns_run.sh"
mkdir -p "$out/runs/cache"
if [ -n "${START_PLAN:-}" ]; then
  "$netns" "$bin" demo --plan "$START_PLAN" --json --no-report --run-root "$out/runs" \
    --run-dir "$out/reference" > "$out/reference.json" 2> "$out/reference.err"
else
  "$netns" "$bin" demo --json --no-report --run-root "$out/runs" --run-dir "$out/reference" \
    > "$out/reference.json" 2> "$out/reference.err"
fi
for s in "${seeds[@]}"; do
  t0=$(date +%s.%N)
  args=(demo --truth "$truth" --identify --seed "$s" --json --no-report --run-root "$out/runs"
        --run-dir "$out/s$s")
  [ -z "${START_PLAN:-}" ] || args+=(--plan "$START_PLAN")
  code=0
  "$netns" "$bin" "${args[@]}" > "$out/s$s.json" 2> "$out/s$s.err" || code=$?
  python3 - "$out/s$s.json" "$out/reference.json" "$s" "$code" "$t0" "$(date +%s.%N)" <<'PY'
import json, sys
loop_file, ref_file, seed, code, t0, t1 = sys.argv[1:]
try:
    d = json.load(open(loop_file))
except ValueError:
    print("seed %s: the loop failed (exit %s)" % (seed, code)); sys.exit(0)
r = json.load(open(ref_file))
b, a, p = d["before"], d["after"], d["identify"].get("parameters", {})
if not a:  # verdict none / unexplained: nothing was added to the model, no second run
    print("seed %s: %s, no run after (exit %s)" % (seed, d["identify"].get("verdict"), code))
    sys.exit(0)
print("seed %s: %s %s, mass %.3f kg, m c = (%.3f, %.3f, %.3f) kg m | tracking %.2f -> %.2f mrad "
      "(%+.0f %%), effort %.4f -> %.4f (%+.0f %%), cleared %s -> %s | no payload %.2f mrad / %.4f "
      "| %.0f s" % (
          seed, d["identify"]["verdict"], d["identify"].get("effect", ""), p.get("mass", 0.0),
          p.get("mass*offset_x", 0.0), p.get("mass*offset_y", 0.0), p.get("mass*offset_z", 0.0),
          1e3 * b["tracking_rms"], 1e3 * a["tracking_rms"],
          100 * (a["tracking_rms"] / b["tracking_rms"] - 1), b["stabilizer_effort"],
          a["stabilizer_effort"], 100 * (a["stabilizer_effort"] / b["stabilizer_effort"] - 1),
          b["cleared"], a["cleared"], 1e3 * r["tracking_rms"], r["stabilizer_effort"],
          float(t1) - float(t0)))
PY
done
