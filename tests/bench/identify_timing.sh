#!/usr/bin/env bash
# Identification timing (issue 8: a 5 s log in under 30 s on 2 cores): a 5 s excitation plan
# replayed on the simulator with a 2 kg chest payload (overstep demo, inside a private network
# namespace: needs root), then `overstep identify` on its log, timed.
# Usage: tests/bench/identify_timing.sh [BUILD_DIR]
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
build=${1:-build}
bin=$(realpath "$build/app/overstep")
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
"$bin" plan --excite 5 --out "$out/excite.json" 2>/dev/null
printf 'payload:\n  - {link: CHEST_LINK1, mass: 2.0, offset: [0.05, 0.0, 0.1]}\n' > "$out/truth.yaml"
cat > "$out/run.sh" <<RUN
#!/usr/bin/env bash
set -eu
"$bin" demo --plan "$out/excite.json" --allow-invalid-plan --truth "$out/truth.yaml" \
  --run-dir "$out/run" --no-report --json > "$out/verdict.json" 2> "$out/demo.err" || true
test -s "$out/run/bus.lcmlog"  # (the verdict is "not cleared": the experiment stands still)
RUN
chmod +x "$out/run.sh"
"$here/../integration/netns_run.sh" "$out/run.sh"
start=$(date +%s.%N)
"$bin" identify "$out/run/bus.lcmlog" --plan "$out/excite.json" --json > "$out/identify.json"
end=$(date +%s.%N)
python3 - "$out/identify.json" "$start" "$end" <<'PY'
import json, sys
r = json.load(open(sys.argv[1]))
print("identify: %d ticks (%.1f s), %.2f s wall; verdict %s %s, mass %.3f kg" % (
    r["samples"], r["samples"] / 200.0, float(sys.argv[3]) - float(sys.argv[2]), r["verdict"],
    r["effect"], r["parameters"].get("mass", float("nan"))))
PY
