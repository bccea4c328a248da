#!/usr/bin/env bash
# The Debian packages (.ci/install-deps --cross: host build, tests, ARM
# cross compilers, qemu-user, the targets' libcamera), the tools' versions,
# and the data sets of the needs-data tests.
source .ci/lib.sh

bash .ci/install-deps --cross
cmake --version | head -n 1
c++ --version | head -n 1
clang++ --version | head -n 1
clang-format --version
qemu-aarch64 --version | head -n 1
# Tests labelled needs-data read data sets that are not Debian packages from
# KG_DATA_DIR (tests/support/data_dir.h). Here every one of them must be
# registered: .ci/run sets KG_REQUIRE_TEST_DATA, so configuring fails on a
# missing set (tests/CMakeLists.txt) instead of leaving its tests out.
if [[ -d $KG_DATA_DIR/oxford && -d $KG_DATA_DIR/real ]]; then
  echo "test data (KG_DATA_DIR): $KG_DATA_DIR"
else
  echo "WARNING: no $KG_DATA_DIR/oxford or $KG_DATA_DIR/real: configuring the ci preset will fail" >&2
fi
