#!/usr/bin/env bash
# Benchmarks are measured by hand (docs/RESULTS.md); here they only have to
# build (the ci preset) and run: each case once, at the smallest size.
source .ci/lib.sh

bench=build/ci/tests/bench
"$bench/bench_search" --benchmark_filter='/10000$' --benchmark_min_time=0.01 2>&1 |
  grep -E '^(radius|knn)/' | sed 's/^/  /'
# The index-size benchmark at its smallest index.
"$bench/bench_index_size" --benchmark_filter='BoxInBoxInScene/1$' --benchmark_min_time=0.01 2>&1 |
  grep -E '^BM_' | sed 's/^/  /'
# The frame benchmark on one of its frames (its summary line included).
"$bench/bench_frame" --benchmark_filter='/fruits$' --benchmark_min_time=0.01 2>&1 |
  tail -n 12 | sed 's/^/  /'
