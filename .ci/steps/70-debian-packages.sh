#!/usr/bin/env bash
# Debian packages (CPack, cmake/KeygraphPackage.cmake): libkeygraph-dev
# (static libraries, headers, CMake package, pkg-config file) and keygraph
# (the tool) for the host (build/ci) and both ARM targets (the cross-builds).
# Checked: the Architecture field, the expected files (dpkg-deb --contents),
# the dependencies (OpenCV for the desktop tool, libcamera for every tool),
# the packaged tool's ELF machine. The host's packages are unpacked into a
# scratch root (dpkg-deb -x: nothing is installed system-wide), where
# `keygraph demo` runs and docs/example builds against the unpacked CMake
# package; the ARM tools run `inspect` from their scratch roots under qemu.
source .ci/lib.sh

VERSION=$(head -n 1 VERSION)
summary=()
dev_files=(include/keygraph/detector.h include/keygraph/platform/frame_source.h
  include/keygraph/platform/libcamera/libcamera_source.h lib/libkeygraph_core.a
  lib/libkeygraph_platform.a lib/libkeygraph_platform_files.a lib/libkeygraph_platform_v4l2.a
  lib/libkeygraph_platform_libcamera.a lib/cmake/keygraph/keygraphConfig.cmake
  lib/cmake/keygraph/keygraphCoreTargets.cmake lib/pkgconfig/keygraph.pc)
for target in ci:amd64:x86_64-linux-gnu:Advanced\ Micro\ Devices\ X86-64 \
  cross-aarch64:arm64:aarch64-linux-gnu:AArch64 cross-armhf:armhf:arm-linux-gnueabihf:ARM; do
  IFS=: read -r preset deb_arch triple machine <<<"$target"
  echo "-- $preset ($deb_arch)"
  out=$KG_CI_TMP/deb-$deb_arch
  if ! cpack --config "build/$preset/CPackConfig.cmake" -B "$out" >"$out.log" 2>&1; then
    tail -n 30 "$out.log" >&2
    fail "cpack for $preset (its log's tail above)"
  fi
  tool_depends=(libc6 libstdc++6 libcamera0.0.3)
  if [[ $deb_arch == amd64 ]]; then
    tool_depends+=(libopencv-core406 libopencv-imgcodecs406)
  fi
  root=$KG_CI_TMP/deb-root-$deb_arch
  mkdir -p "$root"
  for pkg in libkeygraph-dev keygraph; do
    deb=$out/${pkg}_${VERSION}_${deb_arch}.deb
    [[ -f $deb ]] || fail "cpack made no $deb; it made: $(ls "$out"/*.deb 2>/dev/null)"
    got_arch=$(dpkg-deb -f "$deb" Architecture)
    [[ $got_arch == "$deb_arch" ]] || fail "$deb: Architecture $got_arch, expected $deb_arch"
    contents=$(dpkg-deb --contents "$deb" | awk '{print $6}' | grep -v '/$')
    if [[ $pkg == keygraph ]]; then expected=(bin/keygraph); else expected=("${dev_files[@]}"); fi
    for f in "${expected[@]}"; do
      if ! grep -qx "\./usr/$f" <<<"$contents"; then
        sed 's/^/  /' <<<"$contents" >&2
        fail "$deb has no /usr/$f; its files are above"
      fi
    done
    depends=$(dpkg-deb -f "$deb" Depends)
    if [[ $pkg == keygraph ]]; then
      depends_names=$(sed 's/ ([^)]*)//g; s/, */\n/g' <<<"$depends")
      for d in "${tool_depends[@]}"; do
        grep -qxF "$d" <<<"$depends_names" || fail "$deb: Depends lacks $d: $depends"
      done
    fi
    dpkg-deb -x "$deb" "$root"
    echo "  $(basename "$deb"): $(stat -c %s "$deb") bytes, $(wc -l <<<"$contents") files; Depends: $depends"
  done
  got=$(elf_machine "$root/usr/bin/keygraph")
  [[ $got == "$machine" ]] || fail "packaged keygraph ($deb_arch) is '$got', expected $machine"
  if [[ $deb_arch == amd64 ]]; then
    # The tool from the scratch root: the demo reads box.png from opencv-doc.
    mkdir -p "$KG_CI_TMP/deb-demo"
    "$root/usr/bin/keygraph" demo --out "$KG_CI_TMP/deb-demo" >"$KG_CI_TMP/deb-demo.log"
    if ! grep -q '1 detection' "$KG_CI_TMP/deb-demo.log" || [[ ! -s $KG_CI_TMP/deb-demo/demo.png ]]; then
      cat "$KG_CI_TMP/deb-demo.log" >&2
      fail "keygraph demo from the unpacked package (its output above)"
    fi
    sed 's/^/  packaged keygraph demo: /' "$KG_CI_TMP/deb-demo.log"
    cmake -S docs/example -B "$KG_CI_TMP/example-deb" -DCMAKE_PREFIX_PATH="$root/usr" \
      -DCMAKE_BUILD_TYPE=Release -DCMAKE_FIND_PACKAGE_NO_PACKAGE_REGISTRY=ON >/dev/null
    cmake --build "$KG_CI_TMP/example-deb" -j "$KG_CI_JOBS" >/dev/null
    run_example "find_package consumer of the unpacked libkeygraph-dev" \
      "$KG_CI_TMP/example-deb/keygraph_example"
  else
    qemu=qemu-aarch64
    [[ $deb_arch == armhf ]] && qemu=qemu-arm
    if command -v "$qemu" >/dev/null; then
      "$qemu" -L "$(qemu_root "$triple")" "$root/usr/bin/keygraph" inspect "$GOLDEN_INDEX" |
        grep -E '^total:' | sed "s/^/  packaged keygraph ($deb_arch) under $qemu, inspect: /"
    fi
  fi
  summary+=("$deb_arch: $(cd "$out" && ls -- *.deb | tr '\n' ' ')")
done
printf '  %s\n' "${summary[@]}"
