#!/usr/bin/env bash
# The whole test suite under AddressSanitizer + UBSan, and the libFuzzer
# targets, from one clang build (preset sanitize: -O1 -g, every target
# instrumented for libFuzzer's coverage too; step 90 runs the fuzzers).
source .ci/lib.sh

cmake --preset sanitize >/dev/null
cmake --build --preset sanitize -j "$KG_CI_JOBS"
run_ctest sanitize
