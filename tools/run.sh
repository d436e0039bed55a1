#!/usr/bin/env bash
# README command 1: install dependencies, build, and run the main job on the embedded defaults.
# Until the full demo exists the main job is the most complete pipeline that works: load and
# validate the HRP-2-class model and print its summary (overstep model).
set -euo pipefail
cd "$(dirname "$0")/.."
bash tools/setup.sh
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build build -j"$(nproc)"
./build/app/overstep model "$@"
