#!/usr/bin/env bash
# The README's build with the ci preset: Release with assertions kept (-O2,
# no NDEBUG), warnings are errors, tests and benchmarks built.
source .ci/lib.sh

cmake --preset ci
cmake --build --preset ci -j "$KG_CI_JOBS"
