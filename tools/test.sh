#!/usr/bin/env bash
# README command 2: install dependencies, build with -Werror, check formatting, run every test;
# then an AddressSanitizer/UBSan build runs the unit tests. Exit status: non-zero on any failure.
# OVERSTEP_SKIP_SANITIZE=1 skips the sanitizer job (local iteration only).
set -euo pipefail
cd "$(dirname "$0")/.."
jobs=$(nproc)
bash tools/setup.sh
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release -DOVERSTEP_WERROR=ON >/dev/null
cmake --build build -j"$jobs"
bash tools/check_format.sh
ctest --test-dir build -j"$jobs" --output-on-failure --timeout 1500
if [ "${OVERSTEP_SKIP_SANITIZE:-0}" != 1 ]; then
  echo "== sanitizer job (ASan + UBSan): unit tests"
  cmake -S . -B build-asan -G Ninja -DCMAKE_BUILD_TYPE=Debug -DCMAKE_CXX_FLAGS_DEBUG="-g1 -O1" \
        -DOVERSTEP_WERROR=ON -DOVERSTEP_SANITIZE=ON -DOVERSTEP_BUILD_BENCH=OFF >/dev/null
  cmake --build build-asan -j"$jobs" --target unit_tests  # only what this job runs
  # Problem.EqualityJacobianIsWellConditioned (142 s under ASan, 8 s in Release, where it runs)
  # makes room for the fuzz targets (label unit, tests/fuzz/README.md); so do the restoration
  # paths of Problem.RestorationStopsWhereAcceptTakesAPoint (75 steps, 13 s in Release) and
  # Problem.ProjectionEndsAtTheToleranceOnThePolishPath (up to 90 steps, 17 s in Release, 202 s
  # under ASan), and Problem.EachObjectiveTermsGradientMatchesCentralDifferences (10 s in
  # Release, 104 s under ASan; the code paths of Problem.DerivativesMatchFineCentralDifferences,
  # which runs here).
  ASAN_OPTIONS=detect_leaks=0 ctest --test-dir build-asan -j"$jobs" -L unit \
    -E '^Problem\.(EqualityJacobianIsWellConditioned|RestorationStopsWhereAcceptTakesAPoint|ProjectionEndsAtTheToleranceOnThePolishPath|EachObjectiveTermsGradientMatchesCentralDifferences)$' \
    --output-on-failure --timeout 1500
fi
