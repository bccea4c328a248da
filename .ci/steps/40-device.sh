#!/usr/bin/env bash
# The core alone, as a device application links it (preset device: no
# OpenCV, no tools, no tests; Release -O3 with NDEBUG, warnings are errors,
# x86-64's SIMD paths).
source .ci/lib.sh

cmake --preset device >/dev/null
cmake --build --preset device -j "$KG_CI_JOBS"
