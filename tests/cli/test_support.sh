# What the shell tests of the keygraph tool share. Sourced after setting
# TEST_NAME (the test's name, also the scratch folder's prefix):
#   TEST_NAME=cli_x; . "$(dirname "$0")/test_support.sh"
# It gives $WORK (a scratch folder removed at exit, also on a signal), $OUT
# and $ERR (the last run's output), the counters $failures and $checks, and:
#   bad MESSAGE...     records a failed check and prints it on stderr
#   run CMD...         runs CMD: stdout in $OUT, stderr in $ERR, status in $rc
#   one_error CODE NEEDLE
#                      true when the last run exited CODE with exactly one
#                      stderr line, containing NEEDLE
#   finish             the summary line; exits 1 if a check failed
WORK=$(mktemp -d "${TMPDIR:-/tmp}/kg_${TEST_NAME:?set TEST_NAME before sourcing test_support.sh}.XXXXXX") || exit 1
trap 'rm -rf "$WORK"' EXIT
trap 'exit 1' HUP INT TERM
OUT=$WORK/stdout
ERR=$WORK/stderr
failures=0
checks=0

bad() {
  echo "FAIL: $*" >&2
  failures=$((failures + 1))
}

run() {
  checks=$((checks + 1))
  "$@" >"$OUT" 2>"$ERR"
  rc=$?
}

one_error() {
  [ "$rc" -eq "$1" ] && [ "$(wc -l <"$ERR")" -eq 1 ] && grep -qF -- "$2" "$ERR"
}

finish() {
  if [ "$failures" -ne 0 ]; then
    echo "$TEST_NAME: $failures failure(s)" >&2
    exit 1
  fi
  echo "$TEST_NAME: all checks passed"
  exit 0
}
