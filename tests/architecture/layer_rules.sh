#!/bin/sh
# The layer rules (cmake/check_layers.cmake) pass on the tree and catch a
# violation: a copy of the tree whose core includes an OpenCV header and
# whose builder includes the CLI must fail with one line for each.
#   layer_rules.sh SOURCE_DIR
set -eu
ROOT=$1
cmake -DROOT="$ROOT" -P "$ROOT/cmake/check_layers.cmake"
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT
mkdir -p "$TMP/tree"
cp -R "$ROOT/include" "$ROOT/src" "$ROOT/platform" "$TMP/tree/"
printf '#include <opencv2/core.hpp>\n' >>"$TMP/tree/src/core/detector.cpp"
printf '#include "cli/device/json.h"\n' >>"$TMP/tree/src/builder/model_builder.cpp"
printf '#include "core/index/kdtree.h"\n' >>"$TMP/tree/include/keygraph/detector.h"
if cmake -DROOT="$TMP/tree" -P "$ROOT/cmake/check_layers.cmake" >"$TMP/out" 2>&1; then
  echo "FAILED: the layer check passed a tree with three violations" >&2
  exit 1
fi
for expected in "src/core/detector.cpp: src/core may not include opencv2/core.hpp" \
  "src/builder/model_builder.cpp: src/builder may not include cli/device/json.h" \
  "include/keygraph/detector.h: include/keygraph may not include core/index/kdtree.h" \
  "3 violation(s)"; do
  if ! grep -qF "$expected" "$TMP/out"; then
    echo "FAILED: the layer check did not report: $expected; it said:" >&2
    cat "$TMP/out" >&2
    exit 1
  fi
done
echo "layer rules: the tree passes; a tree with 3 violations fails naming each"
