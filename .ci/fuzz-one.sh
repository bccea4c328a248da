#!/usr/bin/env bash
# Runs one libFuzzer target for a while (step 90):
#   bash .ci/fuzz-one.sh FUZZER SECONDS WORK_DIR [SEED_DIR...]
# New inputs go to WORK_DIR/corpus-NAME, crashes to WORK_DIR/artifacts, the
# log to WORK_DIR/log-NAME. Prints libFuzzer's final stats; fails on a
# sanitizer report, a libFuzzer error or a non-zero exit, with the report
# and the command that reproduces it.
set -euo pipefail
fuzzer=$1 seconds=$2 work=$3
shift 3
name=$(basename "$fuzzer")
log=$work/log-$name
mkdir -p "$work/corpus-$name" "$work/artifacts"
rc=0
UBSAN_OPTIONS=print_stacktrace=1 "$fuzzer" "$work/corpus-$name" "$@" \
  -max_total_time="$seconds" -rss_limit_mb=2048 -timeout=30 -print_final_stats=1 \
  -artifact_prefix="$work/artifacts/$name-" >"$log" 2>&1 || rc=$?
# libFuzzer's final stats, then the harness's own summary line, if any.
grep -E "^(Done [0-9]+ runs|stat::number_of_executed_units|stat::peak_rss_mb|$name:)" "$log" |
  sed "s/^/  $name: /" || true
if [[ $rc -ne 0 ]] || grep -qE 'ERROR: (AddressSanitizer|LeakSanitizer|libFuzzer)|runtime error:' "$log"; then
  # To stderr, and to the step's failure report (printed again at the end
  # of the log by .ci/run) when there is one.
  {
    echo "FAILED: $name (exit $rc); the report:"
    grep -B2 -A40 -m1 -E 'ERROR: |runtime error:' "$log" || tail -n 60 "$log"
    echo "reproduce: UBSAN_OPTIONS=print_stacktrace=1 $fuzzer" \
      "$(ls "$work/artifacts/$name"-* 2>/dev/null | head -n 1)"
  } | tee -a "${KG_CI_REPORT:-/dev/null}" >&2
  exit 1
fi
