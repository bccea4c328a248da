#!/bin/bash
# The C API and the bindings as an installed keygraph gives them:
# `cmake --install` of the build tree into a temporary prefix, then on the
# bindings' scenes (make_scenes.sh):
#   1. a C99 program (tests/capi/find.c) built with `pkg-config --cflags
#      --libs keygraph-c` and the C compiler alone;
#   2. the same through find_package(keygraph COMPONENTS capi) in a C-only
#      CMake project;
#   3. Python: PYTHONPATH=<prefix>/lib/python3/dist-packages, `import
#      keygraph` and tests/python/find_scenes.py;
#   4. Java: <prefix>/share/java/keygraph.jar with <prefix>/lib/jni.
# Each must find the box in box_in_scene.pgm and the graf crop in graf3.pgm.
#
# usage: install_bindings.sh BUILD_DIR SOURCE_DIR CMAKE CC SCENES_DIR PYTHON JAVA TEST_JAR
#        GENERATOR MAKE_PROGRAM   (PYTHON, JAVA, TEST_JAR: "" when not built)
set -u
BUILD=${1:?} SRC=${2:?} CMAKE=${3:?} CC=${4:?} SCENES=${5:?}
PYTHON=${6:-} JAVA=${7:-} TEST_JAR=${8:-}
GENERATOR=(-G "${9:?}" -DCMAKE_MAKE_PROGRAM="${10:?}")

TMP=$(mktemp -d "${TMPDIR:-/tmp}/kg-bindings.XXXXXX") || exit 1
trap 'rm -rf "$TMP"' EXIT
PREFIX=$TMP/prefix
passed=0 failed=0
bad() {
  echo "FAIL: $*" >&2
  failed=$((failed + 1))
}
# finds WHAT CMD...: CMD prints the box in box_in_scene and graf in graf3.
finds() {
  local what=$1
  shift
  if ! "$@" "$SCENES/scenes.kgi" "$SCENES/box_in_scene.pgm" "$SCENES/graf3.pgm" >"$TMP/out" 2>&1; then
    bad "$what failed: $(cat "$TMP/out")"
  elif grep -q '^box_in_scene.pgm box ' "$TMP/out" && grep -q '^graf3.pgm graf ' "$TMP/out"; then
    echo "ok: $what"
    sed 's/^/    /' "$TMP/out"
    passed=$((passed + 1))
  else
    bad "$what did not find box and graf: $(cat "$TMP/out")"
  fi
}

if ! "$CMAKE" --install "$BUILD" --prefix "$PREFIX" >"$TMP/install.log" 2>&1; then
  cat "$TMP/install.log" >&2
  echo "0 passed, 1 failed"
  exit 1
fi
for f in include/keygraph/keygraph.h lib/libkeygraph_capi.a lib/pkgconfig/keygraph-c.pc \
  lib/cmake/keygraph/keygraphCapiTargets.cmake; do
  [[ -f $PREFIX/$f ]] || bad "not installed: $f"
done

# 1. pkg-config and the C compiler alone.
export PKG_CONFIG_PATH=$PREFIX/lib/pkgconfig
if flags=$(pkg-config --cflags --libs keygraph-c 2>"$TMP/pc.log"); then
  # shellcheck disable=SC2086
  if "$CC" -std=c99 -Wall -Wextra -pedantic -Werror "$SRC/tests/capi/find.c" "$SRC/tests/capi/pgm_read.c" \
    $flags -o "$TMP/find_pc" >"$TMP/cc.log" 2>&1; then
    finds "C program built with pkg-config keygraph-c ($flags)" "$TMP/find_pc"
  else
    bad "C program with pkg-config keygraph-c: $(cat "$TMP/cc.log")"
  fi
else
  bad "pkg-config keygraph-c: $(cat "$TMP/pc.log")"
fi

# 2. find_package in a project whose only language is C.
mkdir -p "$TMP/app"
cat >"$TMP/app/CMakeLists.txt" <<CMAKE
cmake_minimum_required(VERSION 3.22)
project(find_c LANGUAGES C)
find_package(keygraph REQUIRED COMPONENTS capi)
add_executable(find_c $SRC/tests/capi/find.c $SRC/tests/capi/pgm_read.c)
set_target_properties(find_c PROPERTIES C_STANDARD 99 C_EXTENSIONS OFF)
target_link_libraries(find_c PRIVATE keygraph::capi)
CMAKE
if "$CMAKE" -S "$TMP/app" -B "$TMP/app/build" "${GENERATOR[@]}" -DCMAKE_C_COMPILER="$CC" \
  -DCMAKE_PREFIX_PATH="$PREFIX" >"$TMP/app.log" 2>&1 &&
  "$CMAKE" --build "$TMP/app/build" >>"$TMP/app.log" 2>&1; then
  finds "C program built with find_package(keygraph COMPONENTS capi)" "$TMP/app/build/find_c"
else
  bad "find_package(keygraph COMPONENTS capi) in a C project: $(cat "$TMP/app.log")"
fi

# 3. Python from the prefix.
if [[ -n $PYTHON ]]; then
  site=$PREFIX/lib/python3/dist-packages
  [[ -f $site/keygraph/__init__.py && -f $site/keygraph/libkeygraph_python.so ]] ||
    bad "the Python package is not in $site"
  finds "Python, PYTHONPATH=<prefix>/lib/python3/dist-packages" \
    env PYTHONPATH="$site" PYTHONDONTWRITEBYTECODE=1 "$PYTHON" "$SRC/tests/python/find_scenes.py"
fi

# 4. Java from the prefix.
if [[ -n $JAVA ]]; then
  finds "Java, <prefix>/share/java/keygraph.jar and <prefix>/lib/jni" \
    "$JAVA" -Djava.library.path="$PREFIX/lib/jni" -cp "$PREFIX/share/java/keygraph.jar:$TEST_JAR" \
    org.keygraph.test.FindScenes
fi
echo "$passed passed, $failed failed"
((failed == 0))
