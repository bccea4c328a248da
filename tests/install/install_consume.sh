#!/bin/bash
# The installed keygraph as a user meets it: `cmake --install` of this build
# tree into a temporary prefix, then
#   1. the installed files: every public header, library, CMake and
#      pkg-config file and the licence; no builder, no internal header;
#   2. docs/example through find_package(keygraph COMPONENTS core files v4l2),
#      run on a real index and PGM frames (one larger than the default
#      640x480 limits: the camera example sizes its detector for them);
#   3. a core-only consumer where CMake and pkg-config can find nothing but
#      the prefix (no OpenCV, no libcamera): find_package(keygraph COMPONENTS
#      core) configures and builds, while asking for a component that needs
#      OpenCV or libcamera fails there with a message naming it (so the
#      sandbox really lacks them); no COMPONENTS loads what can be loaded;
#      a "builder" component is refused with the reason;
#   4. the older "platform/..." include spelling through the CMake targets;
#   5. pkg-config: each installed header compiled alone with its own
#      library's `pkg-config --cflags` and nothing else, docs/example/main.cpp
#      and camera.cpp built and run with `pkg-config --cflags --libs`.
#
# usage: install_consume.sh BUILD_DIR SOURCE_DIR CMAKE CXX KEYGRAPH KG_TO_PGM
#                           OPENCV_DATA_DIR FILES_HAVE_OPENCV(ON|OFF) GENERATOR MAKE_PROGRAM
set -u

BUILD=${1:?usage: install_consume.sh BUILD_DIR SOURCE_DIR CMAKE CXX KEYGRAPH KG_TO_PGM DATA FILES_OPENCV}
SRC=${2:?}
CMAKE=${3:?}
CXX=${4:?}
KG=${5:?}
TO_PGM=${6:?}
DATA=${7:?}
FILES_OPENCV=${8:-OFF}
# The consumers are configured with this build's generator and its build
# program, given by path: the sandbox below searches no system paths.
GENERATOR=(-G "${9:?}" -DCMAKE_MAKE_PROGRAM="${10:?}")
case $FILES_OPENCV in ON | TRUE | 1) FILES_OPENCV=1 ;; *) FILES_OPENCV=0 ;; esac

TMP=$(mktemp -d "${TMPDIR:-/tmp}/kg-install.XXXXXX") || exit 1
trap 'rm -rf "$TMP"' EXIT
trap 'exit 1' HUP INT TERM
PREFIX=$TMP/prefix
failures=0
checks=0
bad() {
  echo "FAIL: $*" >&2
  failures=$((failures + 1))
}
check() { checks=$((checks + 1)); }
# quiet LOG CMD...: runs CMD with its output in $TMP/LOG; prints it on failure.
quiet() {
  local log=$TMP/$1
  shift
  if ! "$@" >"$log" 2>&1; then
    echo "command failed: $*" >&2
    sed 's/^/    /' "$log" >&2
    return 1
  fi
}

# --- 1. install and the installed files -------------------------------------
quiet install.log "$CMAKE" --install "$BUILD" --prefix "$PREFIX" || {
  echo "install_consume: cmake --install failed" >&2
  exit 1
}
CORE_LIB=$(find "$PREFIX" -name libkeygraph_core.a -print -quit)
[ -n "$CORE_LIB" ] || {
  echo "install_consume: no libkeygraph_core.a in $PREFIX" >&2
  exit 1
}
LIBDIR=$(dirname "$CORE_LIB")
PCDIR=$LIBDIR/pkgconfig
CMAKEDIR=$LIBDIR/cmake/keygraph
INC=$PREFIX/include
HAVE_LIBCAMERA=0
[ -f "$BUILD/platform/libkeygraph_platform_libcamera.a" ] && HAVE_LIBCAMERA=1

expected=(
  "$INC"/keygraph/{detector,image,model_index,params,status,types}.h
  "$INC"/keygraph/platform/{frame_source,convert}.h
  "$INC"/keygraph/platform/files/{file_source,pgm}.h
  "$INC"/keygraph/platform/v4l2/{v4l2_source,system_io}.h
  "$LIBDIR"/libkeygraph_{core,platform,platform_files,platform_v4l2}.a
  "$PCDIR"/keygraph{,-platform,-files,-v4l2}.pc
  "$CMAKEDIR"/keygraph{Config,ConfigVersion,CoreTargets,PlatformTargets,FilesTargets,V4l2Targets}.cmake
  "$CMAKEDIR"/keygraphToolTargets.cmake
  "$PREFIX"/share/doc/{libkeygraph-dev,keygraph}/copyright
  "$PREFIX"/bin/keygraph
)
if ((HAVE_LIBCAMERA)); then
  expected+=("$INC"/keygraph/platform/libcamera/libcamera_source.h "$LIBDIR"/libkeygraph_platform_libcamera.a
    "$PCDIR"/keygraph-libcamera.pc "$CMAKEDIR"/keygraphLibcameraTargets.cmake)
fi
for f in "${expected[@]}"; do
  check
  [ -f "$f" ] || bad "not installed: ${f#"$PREFIX"/}"
done
check
cmp -s "$SRC/LICENSE" "$PREFIX/share/doc/libkeygraph-dev/copyright" ||
  bad "share/doc/libkeygraph-dev/copyright is not LICENSE"
# Not installed: the builder and the evaluation (internal interfaces), the
# file helpers' internal headers.
check
unexpected=$(cd "$PREFIX" && find . \( -name '*builder*' -o -name '*eval*' -o -name held_stderr.h \
  -o -name regular_file.h -o -name output_file.h -o -name image_limits.h -o -name jpeg_structure.h \) -print)
[ -z "$unexpected" ] || bad "installed but internal: $unexpected"
# Nothing installed names a keygraph::build or keygraph::builder target
# (the config names the builder only to refuse it).
check
named=$(grep -rlE 'keygraph::build(er)?\b' "$CMAKEDIR" "$PCDIR" 2>/dev/null)
[ -z "$named" ] || bad "installed files name keygraph::build(er): $named"

# --- the index and the frames ---------------------------------------------------
quiet index.log "$KG" build -q "$DATA/box.png" -o "$TMP/box.kgi" || exit 1
FRAMES=$TMP/frames
mkdir "$FRAMES"
# Name order: box_in_scene (512x384, holds the box), then graf1 (800x640,
# over the default limits).
quiet pgm.log "$TO_PGM" "$DATA/box_in_scene.png" "$FRAMES/1_box_in_scene.pgm" || exit 1
quiet pgm.log "$TO_PGM" "$DATA/graf1.png" "$FRAMES/2_graf1.pgm" || exit 1

# run_core NAME BINARY: usage exit 2 without arguments, then the one model of box.kgi.
run_core() {
  local name=$1 bin=$2 rc=0
  check
  "$bin" >/dev/null 2>&1 || rc=$?
  [ "$rc" -eq 2 ] || bad "$name: exit $rc without arguments, expected 2"
  if "$bin" "$TMP/box.kgi" >"$TMP/run.out" 2>"$TMP/run.err"; then
    grep -qx 'models: 1' "$TMP/run.out" || bad "$name: no 'models: 1' in: $(cat "$TMP/run.out")"
  else
    bad "$name failed: $(cat "$TMP/run.err")"
  fi
}
# run_camera NAME BINARY: the camera example on the frames: the box found in
# the first, the larger second frame detected on too (exit 0).
run_camera() {
  local name=$1 bin=$2
  check
  if "$bin" "$TMP/box.kgi" "$FRAMES" >"$TMP/run.out" 2>"$TMP/run.err"; then
    grep -Eq '^frame 0 \(512x384\): 1 detection\(s\)$' "$TMP/run.out" &&
      grep -Eq '^  box, corners' "$TMP/run.out" &&
      grep -Eq '^frame 1 \(800x640\): [0-9]+ detection\(s\)$' "$TMP/run.out" ||
      bad "$name: unexpected output: $(cat "$TMP/run.out")"
  else
    bad "$name failed on $FRAMES: $(cat "$TMP/run.err") $(cat "$TMP/run.out")"
  fi
}

# --- 2. find_package consumer: docs/example ----------------------------------------
NO_REGISTRY=("${GENERATOR[@]}" -DCMAKE_FIND_USE_PACKAGE_REGISTRY=OFF
  -DCMAKE_FIND_USE_SYSTEM_PACKAGE_REGISTRY=OFF)
check
if quiet example.log "$CMAKE" -S "$SRC/docs/example" -B "$TMP/example" -DCMAKE_BUILD_TYPE=Release \
  -DCMAKE_CXX_COMPILER="$CXX" -DCMAKE_PREFIX_PATH="$PREFIX" "${NO_REGISTRY[@]}" &&
  quiet example-build.log "$CMAKE" --build "$TMP/example"; then
  run_core "find_package consumer (keygraph_example)" "$TMP/example/keygraph_example"
  run_camera "find_package consumer (keygraph_camera_example)" "$TMP/example/keygraph_camera_example"
else
  bad "docs/example did not configure and build against $PREFIX"
fi

# --- 3. core only, with nothing but the prefix to find ------------------------------
# CMake searches only CMAKE_PREFIX_PATH (no system or PATH-derived prefixes,
# no registries); pkg-config only the prefix's .pc files.
SANDBOX=(-DCMAKE_CXX_COMPILER="$CXX" -DCMAKE_PREFIX_PATH="$PREFIX" "${NO_REGISTRY[@]}"
  -DCMAKE_FIND_USE_CMAKE_SYSTEM_PATH=OFF -DCMAKE_FIND_USE_SYSTEM_ENVIRONMENT_PATH=OFF
  -DCMAKE_FIND_USE_CMAKE_ENVIRONMENT_PATH=OFF)
sandboxed() { (
  export PKG_CONFIG_LIBDIR="$PCDIR" PKG_CONFIG_PATH=""
  "$@"
); }
# probe NAME COMPONENTS [cmake args...]: configures tests/install/probe in the
# sandbox; its status in $rc, its output in $TMP/probe.log.
probe() {
  local name=$1 components=$2
  shift 2
  rm -rf "$TMP/probe-$name"
  sandboxed "$CMAKE" -S "$SRC/tests/install/probe" -B "$TMP/probe-$name" "${SANDBOX[@]}" \
    -DPROBE_COMPONENTS="$components" "$@" >"$TMP/probe.log" 2>&1
  rc=$?
}
# said TEXT: the probe's output holds TEXT (CMake wraps messages: lines joined).
said() { tr '\n' ' ' <"$TMP/probe.log" | tr -s ' ' | grep -qF -- "$1"; }
check
probe core core
if [ "$rc" -ne 0 ]; then
  bad "COMPONENTS core in the sandbox did not configure: $(cat "$TMP/probe.log")"
else
  grep -q 'probe: core=1 platform=0 files=0 v4l2=0 libcamera=0' "$TMP/probe.log" ||
    bad "COMPONENTS core: $(grep 'probe:' "$TMP/probe.log")"
fi
check
if sandboxed quiet core-example.log "$CMAKE" -S "$SRC/docs/example" -B "$TMP/example-core" \
  "${SANDBOX[@]}" -DCMAKE_BUILD_TYPE=Release -DKEYGRAPH_EXAMPLE_CAMERA=OFF &&
  quiet core-example-build.log "$CMAKE" --build "$TMP/example-core"; then
  run_core "core-only consumer without OpenCV" "$TMP/example-core/keygraph_example"
  [ -e "$TMP/example-core/keygraph_camera_example" ] &&
    bad "core-only consumer: the camera example was built too"
else
  bad "core-only docs/example did not configure and build in the sandbox"
fi
# The sandbox really has no OpenCV and no libcamera: the components that
# need them fail there, naming what is missing.
if ((FILES_OPENCV)); then
  check
  probe files files
  [ "$rc" -ne 0 ] && said 'component files: keygraph::files decodes images with OpenCV imgcodecs, which was not found (Debian: libopencv-dev, or set OpenCV_DIR)' ||
    bad "COMPONENTS files in the sandbox: exit $rc, expected a failure naming OpenCV: $(cat "$TMP/probe.log")"
fi
if ((HAVE_LIBCAMERA)); then
  check
  probe libcamera "core;libcamera"
  [ "$rc" -ne 0 ] && said 'component libcamera: keygraph::libcamera needs libcamera, which pkg-config did not find' ||
    bad "COMPONENTS libcamera in the sandbox: exit $rc, expected a failure naming libcamera: $(cat "$TMP/probe.log")"
fi
# OPTIONAL_COMPONENTS and no COMPONENTS: what can be loaded is.
check
probe none ""
want="core=1 platform=1 files=$((1 - FILES_OPENCV)) v4l2=1 libcamera=0"
[ "$rc" -eq 0 ] && grep -q "probe: $want" "$TMP/probe.log" ||
  bad "no COMPONENTS in the sandbox: exit $rc, expected '$want': $(cat "$TMP/probe.log")"
check
probe builder builder
[ "$rc" -ne 0 ] && said "no 'builder' component: the model builder is not installed (its interface is internal: OpenCV images, model records); make indexes with \`keygraph build\`" ||
  bad "COMPONENTS builder: exit $rc, expected the builder refused: $(cat "$TMP/probe.log")"

# --- 4. the older include spelling through the CMake targets -------------------------
check
quiet old-spelling.log "$CMAKE" -S "$SRC/tests/install/probe" -B "$TMP/probe-old" -DCMAKE_CXX_COMPILER="$CXX" \
  -DCMAKE_PREFIX_PATH="$PREFIX" "${NO_REGISTRY[@]}" -DPROBE_COMPONENTS="files;v4l2" -DPROBE_OLD_SPELLING=ON &&
  quiet old-spelling-build.log "$CMAKE" --build "$TMP/probe-old" ||
  bad "\"platform/...\" includes through keygraph::files and keygraph::v4l2 did not build"

# --- 5. pkg-config ---------------------------------------------------------------
export PKG_CONFIG_PATH=$PCDIR
CXXFLAGS=(-std=c++17 -Wall -Wextra -Werror)
# Each installed header alone, with its own library's flags and nothing else.
while IFS= read -r header; do
  rel=${header#"$INC"/}
  case $rel in
    keygraph/platform/files/*) pc=keygraph-files ;;
    keygraph/platform/v4l2/*) pc=keygraph-v4l2 ;;
    keygraph/platform/libcamera/*) pc=keygraph-libcamera ;;
    keygraph/platform/*) pc=keygraph-platform ;;
    *) pc=keygraph ;;
  esac
  check
  # shellcheck disable=SC2046  # the flags are meant to be split
  echo "#include <$rel>" | "$CXX" "${CXXFLAGS[@]}" $(pkg-config --cflags "$pc") -fsyntax-only -x c++ - \
    >"$TMP/header.log" 2>&1 || bad "<$rel> does not compile with pkg-config --cflags $pc: $(cat "$TMP/header.log")"
done < <(find "$INC" -name '*.h' | sort)
check
# shellcheck disable=SC2046
if quiet pc-core.log "$CXX" "${CXXFLAGS[@]}" "$SRC/docs/example/main.cpp" \
  $(pkg-config --cflags --libs keygraph) -o "$TMP/pc-example"; then
  run_core "pkg-config consumer (main.cpp)" "$TMP/pc-example"
else
  bad "docs/example/main.cpp did not build with pkg-config --cflags --libs keygraph"
fi
check
# shellcheck disable=SC2046
if quiet pc-camera.log "$CXX" "${CXXFLAGS[@]}" "$SRC/docs/example/camera.cpp" \
  $(pkg-config --cflags --libs keygraph-v4l2 keygraph-files) -o "$TMP/pc-camera"; then
  run_camera "pkg-config consumer (camera.cpp)" "$TMP/pc-camera"
else
  bad "docs/example/camera.cpp did not build with pkg-config keygraph-v4l2 keygraph-files"
fi
# The core's .pc needs no other package; keygraph-files does when it has
# OpenCV (so the sandbox again lacks it).
check
sandboxed pkg-config --cflags --libs keygraph >"$TMP/pc.log" 2>&1 ||
  bad "pkg-config keygraph with the prefix alone: $(cat "$TMP/pc.log")"
if ((FILES_OPENCV)); then
  check
  sandboxed pkg-config --cflags keygraph-files >"$TMP/pc.log" 2>&1 &&
    bad "pkg-config keygraph-files found OpenCV with the prefix alone"
fi

if [ "$failures" -ne 0 ]; then
  echo "install_consume: $failures failure(s) in $checks checks" >&2
  exit 1
fi
echo "install_consume: all $checks checks passed (prefix $PREFIX)"
