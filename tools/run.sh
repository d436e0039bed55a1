#!/usr/bin/env bash
# README command 1: install dependencies, build, and run the main job on the embedded defaults:
# `overstep demo` (plan -> simulator + runtime in lockstep -> verdict). Arguments are passed on.
set -euo pipefail
cd "$(dirname "$0")/.."
bash tools/setup.sh
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build build -j"$(nproc)"
./build/app/overstep demo "$@"
