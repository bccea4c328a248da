#!/usr/bin/env bash
# The whole test suite under AddressSanitizer + UBSan, and the libFuzzer
# targets, from one clang build (preset sanitize: -O1 -g, every target
# instrumented for libFuzzer's coverage too; step 90 runs the fuzzers).
source .ci/lib.sh

cmake --preset sanitize >/dev/null
cmake --build --preset sanitize -j "$KG_CI_JOBS"
# Left out here, run in step 30: the two slowest tests under the sanitizers
# (394 and 186 s of 2 cores' time, against 50 and 47 without), whose code
# runs under them in smaller tests all the same: completion over the exact
# search (Selection.CompletedCircuitsRecoverArcsTheSearchBudgetMissed and
# the other Selection tests on the same case, search tests at every budget),
# 4-circuits and arcs end to end (test_keygraph, test_selection and
# test_model_index build, search and select both structures); and
# cli_eval_truth_real, eval --truth's accuracy on the real photos, over 300 s
# under the sanitizers: the readers it goes through are fuzzed in step 90 and
# run under the sanitizers by the TruthManifest tests, cli_eval_truth and
# cli_hostile.
run_ctest sanitize -E '^(Selection\.CompletedCircuitsWithExactSearchEqualBruteForceJoin|Detection\.CircuitFourAndArcStructures|cli_eval_truth_real)$'
