#!/usr/bin/env bash
# Checks that the module graph is enforced: (1) overstep_module() refuses a dependency outside
# OVERSTEP_ALLOWED_<module> at configure time; (2) core/ and stabilizer/ never include DART or LCM,
# and only robots/, sim/ and planner/ include DART. Usage: check_module_graph.sh SOURCE_DIR
set -euo pipefail
src="$1"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
mkdir -p "$tmp/proj/a" "$tmp/proj/b"
echo 'int a() { return 1; }' > "$tmp/proj/a/a.cpp"
echo 'int b() { return 2; }' > "$tmp/proj/b/b.cpp"
cat > "$tmp/proj/CMakeLists.txt" <<CM
cmake_minimum_required(VERSION 3.22)
project(graphcheck CXX)
set(OVERSTEP_DATA_DIR "\${CMAKE_CURRENT_SOURCE_DIR}")
include("$src/cmake/overstep_module.cmake")
set(OVERSTEP_ALLOWED_core "")
set(OVERSTEP_ALLOWED_stabilizer "core")
add_subdirectory(a)
add_subdirectory(b)
CM
echo 'overstep_module(core SOURCES a.cpp)' > "$tmp/proj/a/CMakeLists.txt"
# stabilizer may use core ...
echo 'overstep_module(stabilizer SOURCES b.cpp PUBLIC_DEPS core)' > "$tmp/proj/b/CMakeLists.txt"
cmake -S "$tmp/proj" -B "$tmp/ok" >/dev/null || { echo "FAIL: allowed dependency refused"; exit 1; }
# ... but core may not use stabilizer (a cycle)
echo 'overstep_module(core SOURCES a.cpp PUBLIC_DEPS stabilizer)' > "$tmp/proj/a/CMakeLists.txt"
if cmake -S "$tmp/proj" -B "$tmp/bad" >"$tmp/log" 2>&1; then
  echo "FAIL: forbidden dependency core -> stabilizer was accepted"; exit 1
fi
grep -q "may not depend on 'stabilizer'" "$tmp/log" || { echo "FAIL: wrong message"; cat "$tmp/log"; exit 1; }

bad=0
for dir in core stabilizer; do
  [ -d "$src/$dir" ] || continue
  if grep -rnE '#include *[<"](dart/|lcm/|overstep/[a-z_]+_t\.hpp)' "$src/$dir"; then
    echo "FAIL: $dir/ includes DART or LCM"; bad=1
  fi
done
for dir in "$src"/*/; do
  name=$(basename "$dir")
  case "$name" in robots|sim|planner|tests|build*) continue ;; esac
  if grep -rlE '#include *<dart/' "$dir" 2>/dev/null; then echo "FAIL: $name/ includes DART"; bad=1; fi
done
[ $bad = 0 ] && echo "module graph enforced"
exit $bad
