#!/usr/bin/env bash
# Checks that the lcm-spy jar holds a class for every LCM type. Usage: check_jar.sh JAR TYPE...
set -euo pipefail
jar="$1"; shift
[ -f "$jar" ] || { echo "missing jar: $jar" >&2; exit 1; }
listing=$(unzip -Z1 "$jar" 2>/dev/null || jar tf "$jar")
missing=0
for t in "$@"; do
  if ! grep -qx "overstep/$t.class" <<<"$listing"; then echo "jar lacks overstep/$t.class" >&2; missing=1; fi
done
[ "$missing" = 0 ] && echo "jar holds all $# types"
exit $missing
