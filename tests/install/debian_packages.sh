#!/bin/bash
# The Debian packages of this build tree (cmake/KeygraphPackage.cmake), made
# with cpack into a temporary directory, checked field by field:
#   Description  a short line, then the long description (no CMake list
#                joined by ';': it once began with " ;");
#   copyright    the licence in /usr/share/doc/<package>/copyright, equal to
#                LICENSE;
#   Depends      libkeygraph-dev needs nothing: a core-only user gets no
#                OpenCV or libcamera; what the components need is Suggested;
#   contents     no builder library.
# Any build directory's packages: the host's (ctest) or a cross-build's
# (.ci/run, which checks the rest: architectures, the tool's dependencies
# and ELF machine, the unpacked tool and CMake package).
#
# usage: debian_packages.sh CPACK BUILD_DIR VERSION FILES_HAVE_OPENCV(ON|OFF)
set -u

CPACK=${1:?usage: debian_packages.sh CPACK BUILD_DIR VERSION FILES_HAVE_OPENCV}
BUILD=${2:?}
VERSION=${3:?}
FILES_OPENCV=${4:-OFF}
SRC=$(cd "$(dirname "$0")/../.." && pwd)

TMP=$(mktemp -d "${TMPDIR:-/tmp}/kg-deb.XXXXXX") || exit 1
trap 'rm -rf "$TMP"' EXIT
trap 'exit 1' HUP INT TERM
failures=0
bad() {
  echo "FAIL: $*" >&2
  failures=$((failures + 1))
}

[ -f "$BUILD/CPackConfig.cmake" ] || {
  echo "debian_packages: no $BUILD/CPackConfig.cmake (configure found no dpkg-architecture?)" >&2
  exit 1
}
if ! "$CPACK" --config "$BUILD/CPackConfig.cmake" -B "$TMP/out" >"$TMP/cpack.log" 2>&1; then
  echo "debian_packages: cpack failed:" >&2
  tail -n 30 "$TMP/cpack.log" >&2
  exit 1
fi
# The short descriptions: the tool's is the desktop or the device build's.
declare -A short=(
  [libkeygraph-dev]="keygraph: static libraries and headers"
  [keygraph]="keygraph: build, detect, evaluate and run live detection|keygraph: live detection on a device"
)
arch=
for pkg in libkeygraph-dev keygraph; do
  debs=("$TMP/out/${pkg}_${VERSION}_"*.deb)
  deb=${debs[0]}
  if [ ! -f "$deb" ]; then
    bad "cpack made no ${pkg}_${VERSION}_<arch>.deb; it made: $(cd "$TMP/out" && ls -- *.deb 2>/dev/null)"
    continue
  fi
  arch=$(dpkg-deb -f "$deb" Architecture)
  # dpkg-deb -f prints the short description on the field's line, the long
  # one indented below it.
  description=$(dpkg-deb -f "$deb" Description)
  first=$(head -n 1 <<<"$description")
  grep -qxE "${short[$pkg]}" <<<"$first" || bad "$pkg: Description begins '$first', expected '${short[$pkg]}'"
  grep -q ';' <<<"$description" && bad "$pkg: Description holds ';': $description"
  [ "$(wc -l <<<"$description")" -ge 3 ] || bad "$pkg: no long description: $description"
  grep -vq '^ ' <<<"$(tail -n +2 <<<"$description")" &&
    bad "$pkg: long description lines must start with a space: $description"

  mkdir -p "$TMP/root-$pkg"
  dpkg-deb -x "$deb" "$TMP/root-$pkg"
  cmp -s "$SRC/LICENSE" "$TMP/root-$pkg/usr/share/doc/$pkg/copyright" ||
    bad "$pkg: /usr/share/doc/$pkg/copyright missing or not LICENSE"
  contents=$(dpkg-deb --contents "$deb" | awk '{print $6}')
  grep -q builder <<<"$contents" && bad "$pkg: holds a builder: $(grep builder <<<"$contents")"
done

dev=$TMP/out/libkeygraph-dev_${VERSION}_${arch:-none}.deb
if [ -f "$dev" ]; then
  depends=$(dpkg-deb -f "$dev" Depends)
  grep -Eq 'opencv|libcamera' <<<"$depends" && bad "libkeygraph-dev: Depends on $depends"
  suggests=$(dpkg-deb -f "$dev" Suggests)
  case $FILES_OPENCV in
    ON | TRUE | 1)
      grep -q 'libopencv-dev' <<<"$suggests" || bad "libkeygraph-dev: Suggests lacks libopencv-dev: $suggests"
      ;;
  esac
  dev_contents=$(dpkg-deb --contents "$dev")
  if grep -q 'libkeygraph_platform_libcamera.a' <<<"$dev_contents"; then
    grep -q 'libcamera-dev' <<<"$suggests" || bad "libkeygraph-dev: Suggests lacks libcamera-dev: $suggests"
  fi
fi

if [ "$failures" -ne 0 ]; then
  echo "debian_packages: $failures failure(s)" >&2
  exit 1
fi
echo "debian_packages: libkeygraph-dev and keygraph ($arch): Description, copyright, Depends checked"
