#!/usr/bin/env bash
# Sets up a fresh machine and runs the benchmark suite (medians of repeated runs, ratios against
# the LibTorch / MuJoCo peers measured in the same run). Extra arguments go to every benchmark binary.
set -euo pipefail
cd "$(dirname "$0")/.."
bash .ci/install-deps.sh
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release -DSPARSEBODY_BUILD_BENCH=ON
cmake --build build -j"$(nproc)" --target $(grep -ho 'sparsebody_add_bench([a-z_0-9]*' bench/*.cmake | sed 's/.*(//')
for b in build/bench/bench_*; do
  [ -x "$b" ] || continue
  echo "=== $b"
  "$b" --benchmark_repetitions=5 --benchmark_report_aggregates_only=true "$@"
done
