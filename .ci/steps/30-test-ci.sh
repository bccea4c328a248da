#!/usr/bin/env bash
# The README's test command: the whole suite of the ci build (what the
# suite checks, and what moved into it from this script: docs/CI.md). With
# the data sets present (KG_REQUIRE_TEST_DATA: configuring fails without
# them), the tests labelled needs-data are among them; a registered test
# whose data has gone fails (KG_REQUIRE_DATA, tests/support/data_dir.h), so
# the suite passing means every one of them ran and passed. A failed test
# runs once more with its output, printed at the end of the log (run_ctest).
source .ci/lib.sh

run_ctest ci
needs_data=$(ctest --preset ci -N -L needs-data | sed -n 's/^Total Tests: //p')
((needs_data > 0)) || fail "no test is labelled needs-data (KG_DATA_DIR=$KG_DATA_DIR)"
echo "of them labelled needs-data (KG_DATA_DIR=$KG_DATA_DIR): $needs_data"
