# shellcheck shell=bash
# Helpers the step scripts share (.ci/steps/*.sh source this file). .ci/run
# exports the environment they rely on:
#   KG_CI_JOBS     parallel jobs (2)
#   KG_CI_TMP      scratch directory, removed when .ci/run ends
#   KG_DATA_DIR    the data sets of the needs-data tests
#   OPENCV_DATA    opencv-doc's images
#   KG_CI_SOFT_FAILURE  the exit status of a step whose failure is reported
#                  at the end, after the other steps have run (clang-format)
#   KG_CI_REPORT   a file for the step's failure report: .ci/run prints it
#                  again at the very end of the log, after the step table
#                  (CI shows only the log's tail)
# Steps run from the repository's root with `set -euo pipefail`.
set -euo pipefail

: "${KG_CI_JOBS:=2}"
: "${OPENCV_DATA:=/usr/share/doc/opencv-doc/examples/data}"
: "${KG_CI_SOFT_FAILURE:=3}"
if [[ -z ${KG_CI_TMP:-} || -z ${KG_CI_REPORT:-} ]]; then
  echo "KG_CI_TMP or KG_CI_REPORT is not set: run the steps through .ci/run (bash .ci/run STEP)" >&2
  exit 2
fi

# The stored index of the golden-frame tests (tests/data/frames-box.kgi):
# input for the packaged tools of step 70.
GOLDEN_INDEX=$PWD/tests/data/frames-box.kgi

# fail MESSAGE...: the step fails with MESSAGE, here and again at the end.
fail() {
  echo "FAILED: $*" | tee -a "$KG_CI_REPORT" >&2
  exit 1
}

# run_ctest PRESET [CTEST ARG...]: the test suite of a preset. When a test
# fails, the failed tests run once more, one at a time, with their output
# (a flaky failure then passes, a steady one fails again), and that output
# is the step's failure report, printed again at the end of the log.
run_ctest() {
  local preset=$1
  shift
  ctest --preset "$preset" "$@" && return 0
  echo "ctest --preset $preset failed; the failed tests run again with their output" \
    "(printed at the end of the log)"
  {
    echo "==== ctest --preset $preset: the failed tests once more, one at a time, with their output"
    ctest --preset "$preset" --rerun-failed --output-on-failure -j 1 2>&1 | tail -n 150 || true
  } >>"$KG_CI_REPORT"
  exit 1
}

# elf_machine FILE: the Machine field of an ELF header (every object's, one
# line each distinct value, for a static library).
elf_machine() {
  readelf -h "$1" | awk -F: '/Machine:/ {gsub(/^ +/, "", $2); print $2}' | sort -u
}

# qemu_root TRIPLE: the -L root for qemu-user: the target's loader and libc
# from one package, the multiarch ones when installed (libcamera-dev:<arch>
# brings them), as toolchains/debian-cross.cmake picks it.
qemu_root() {
  if [[ -e /usr/lib/$1/libc.so.6 ]]; then echo /; else echo "/usr/$1"; fi
}

# run_example NAME BINARY [ARG...]: usage exit 2 without arguments, then a
# run on $EXAMPLE_INDEX (default the golden index) and ARGs; under
# $EXAMPLE_EMULATOR (e.g. "qemu-arm -L /") when that is set.
run_example() {
  local name=$1 bin=$2 rc=0 emulator=()
  shift 2
  read -ra emulator <<<"${EXAMPLE_EMULATOR:-}"
  "${emulator[@]}" "$bin" >/dev/null 2>&1 || rc=$?
  [[ $rc -eq 2 ]] || fail "$name: expected exit 2 without arguments, got $rc"
  echo "$name:"
  "${emulator[@]}" "$bin" "${EXAMPLE_INDEX:-$GOLDEN_INDEX}" "$@" | sed 's/^/  /'
}
