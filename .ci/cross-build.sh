#!/usr/bin/env bash
# One ARM cross-build (steps 60 and 61): bash .ci/cross-build.sh aarch64|armhf
# Preset cross-<arch> (toolchains/): the core, the frame sources (V4L2,
# libcamera, files), the core's and platform's tests, the golden-frame tests
# and the device CLI, without OpenCV; then the installed library
# cross-compiles docs/example. Checked: every program and library object is
# an ARM ELF; the device CLI links the target's libcamera and the install
# has its frame source; under qemu-user, the whole cross-built test suite
# (among it tests/core/test_golden_frames.cpp: the box at the stored corners,
# no allocation in detect(); and tests/cli/cli_golden_frames.py: the device
# CLI's detect, live and inspect, and live --libcamera without a camera) and
# the example programs.
source .ci/lib.sh

case ${1:-} in
  aarch64) triple=aarch64-linux-gnu qemu=qemu-aarch64 machine=AArch64 ;;
  armhf) triple=arm-linux-gnueabihf qemu=qemu-arm machine=ARM ;;
  *)
    echo "usage: cross-build.sh aarch64|armhf" >&2
    exit 2
    ;;
esac
arch=$1
preset=cross-$arch
dir=build/$preset
TMP=$KG_CI_TMP/$preset
mkdir -p "$TMP"

cmake --preset "$preset" >/dev/null
cmake --build --preset "$preset" -j "$KG_CI_JOBS"
prefix=$TMP/prefix
cmake --install "$dir" --prefix "$prefix" >/dev/null
cmake -S docs/example -B "$TMP/example" -DCMAKE_PREFIX_PATH="$prefix" \
  -DCMAKE_TOOLCHAIN_FILE="$PWD/toolchains/$triple.cmake" -DCMAKE_BUILD_TYPE=Release \
  -DCMAKE_CXX_FLAGS="-Wall -Wextra -Werror" -DCMAKE_FIND_PACKAGE_NO_PACKAGE_REGISTRY=ON >/dev/null
cmake --build "$TMP/example" -j "$KG_CI_JOBS" >/dev/null

# ARM binaries: the ELF header's machine field of each program and of every
# object in the static libraries.
mapfile -t programs < <(find "$dir/src/cli" "$dir/tests"/* "$TMP/example" -maxdepth 1 \
  -type f -perm -u+x \( -name keygraph -o -name 'test_*' -o -name 'keygraph_*example' \))
mapfile -t libraries < <(find "$prefix/lib" -name 'libkeygraph_*.a')
for f in "${programs[@]}" "${libraries[@]}"; do
  got=$(elf_machine "$f")
  [[ $got == "$machine" ]] || fail "$f: ELF machine '${got:-none}', expected $machine"
done
echo "ARM check: ${#programs[@]} programs and ${#libraries[@]} static libraries are $machine ELF"
core=$dir/src/core/libkeygraph_core.a
core_bytes=$(stat -c %s "$core")
echo "libkeygraph_core.a ($arch): $core_bytes bytes;" \
  "$("$triple-size" -t "$core" | awk 'END {print $1 " text, " $2 " data, " $3 " bss"}') (bytes, all objects)"
readelf -A "$dir/tests/platform/test_convert" | grep -E 'Tag_(CPU_arch|FP_arch|Advanced_SIMD_arch):' |
  sed 's/^ */  /' || true

# libcamera: the cross-builds find the target's libcamera through pkg-config
# (PKG_CONFIG_LIBDIR in toolchains/debian-cross.cmake; Debian's
# libcamera-dev:arm64 and :armhf): the device CLI links it and the install
# has its frame source.
cli=$dir/src/cli/keygraph
readelf -d "$cli" | grep -q 'NEEDED.*\[libcamera\.so' ||
  fail "$cli does not link libcamera (was libcamera-dev:<arch> found? see the configure output)"
lib=$prefix/lib/libkeygraph_platform_libcamera.a
[[ -f $lib ]] || fail "no $lib in the $arch install"
echo "$cli links $(readelf -d "$cli" | grep -o 'libcamera\.so[.0-9]*' | head -n 1);" \
  "$(basename "$lib"): $(stat -c %s "$lib") bytes"

if ! command -v "$qemu" >/dev/null; then
  echo "$qemu not installed: cross-built tests NOT run (apt-get install qemu-user, or bash .ci/install-deps --cross)"
  exit 0
fi
run_ctest "$preset"
export EXAMPLE_EMULATOR="$qemu -L $(qemu_root "$triple")"
run_example "cross-built find_package consumer ($arch, $qemu)" "$TMP/example/keygraph_example"
run_example "cross-built camera example on PGM files ($arch, $qemu)" \
  "$TMP/example/keygraph_camera_example" "$dir/tests/golden-frames"
