#!/usr/bin/env bash
# Instructions an AArch64 keygraph executes per frame, counted under
# qemu-aarch64 by our TCG plugin (insn_count.c): a relative ARM cost that
# does not depend on this machine's load.
#
#   bash tests/tools/qemu_insn_count/run.sh KEYGRAPH INDEX.kgi FRAME.pgm...
#
# KEYGRAPH is an aarch64 device CLI (cmake --preset cross-aarch64; its
# src/cli/keygraph). For each frame and each SIMD level in KG_SIMD_LEVELS
# (default "neon scalar"; the environment variable KG_SIMD that the core
# reads, which binaries before it ignore), `keygraph bench --threads T`
# (KG_THREADS, default 1) runs with --repeat R1 and R2 (KG_REPEAT_FIRST and
# KG_REPEAT_SECOND, default 1 and 3): the difference of the two counts over
# R2 - R1 is one frame's detect(), without the program's start, the index
# load and the first frame's warm-up. With T > 1 the count is also kept per
# thread, and the busiest thread's share is printed: total / busiest is the
# most T threads could gain if instructions were time and no thread waited.
# KG_BENCH_ARGS adds bench options: "--set time_budget_ms=0.001" stops each
# frame after its keypoint stage (the budget is spent by then), so the count
# is the keypoints' alone.
#
# The plugin needs qemu's qemu-plugin.h, which is not in this repository:
# it is fetched once from Debian's source of the installed qemu-user (the
# .orig tarball from the URI apt gives for a deb-src entry, its SHA256
# checked) into KG_QEMU_PLUGIN_CACHE (default ~/.cache/keygraph). When that
# fails (no network, no apt) the script says so and exits 3: no counts.
set -euo pipefail

here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
levels=${KG_SIMD_LEVELS:-neon scalar}
r1=${KG_REPEAT_FIRST:-1}
r2=${KG_REPEAT_SECOND:-3}
threads=${KG_THREADS:-1}

die() {
  echo "keygraph: $1" >&2
  exit "${2:-1}"
}
[[ $# -ge 3 ]] || die "usage: run.sh KEYGRAPH INDEX.kgi FRAME.pgm..." 2
# The names KG_SIMD knows (src/core/support/simd_dispatch.cpp), which
# ignores any other: a typo would count the NEON build twice, silently.
for level in $levels; do
  case $level in
    neon | baseline | scalar) ;;
    *) die "KG_SIMD_LEVELS: unknown level '$level' (neon, baseline or scalar on AArch64)" 2 ;;
  esac
done
keygraph=$1 index=$2
shift 2
[[ -x $keygraph ]] || die "$keygraph: not an executable"
[[ -f $index ]] || die "$index: no such index"
command -v qemu-aarch64 >/dev/null || die "qemu-aarch64 not installed (apt-get install qemu-user)"

# qemu's plugin header, from the Debian source package of the qemu-user installed.
source_version=$(dpkg-query -W -f='${source:Version}' qemu-user 2>/dev/null) ||
  die "cannot tell the installed qemu-user's source version (dpkg-query)"
cache=${KG_QEMU_PLUGIN_CACHE:-${XDG_CACHE_HOME:-$HOME/.cache}/keygraph}/qemu-${source_version//[:\/]/_}
header=$cache/qemu-plugin.h
fetch_header() {
  local tmp codename line uri sum
  tmp=$(mktemp -d)
  trap 'rm -rf "$tmp"' RETURN
  codename=$(. /etc/os-release && echo "${VERSION_CODENAME:-}")
  [[ -n $codename ]] || return 1
  mkdir -p "$tmp/parts" "$tmp/lists/partial"
  cat >"$tmp/parts/src.sources" <<EOF
Types: deb-src
URIs: http://deb.debian.org/debian
Suites: $codename $codename-updates
Components: main
Signed-By: /usr/share/keyrings/debian-archive-keyring.gpg

Types: deb-src
URIs: http://deb.debian.org/debian-security
Suites: $codename-security
Components: main
Signed-By: /usr/share/keyrings/debian-archive-keyring.gpg
EOF
  : >"$tmp/empty.list"
  local apt_options=(-o "Dir::Etc::SourceList=$tmp/empty.list" -o "Dir::Etc::SourceParts=$tmp/parts"
    -o "Dir::State::Lists=$tmp/lists" -o "Dir::Cache=$tmp/cache")
  apt-get "${apt_options[@]}" update >"$tmp/apt.log" 2>&1 || return 1
  line=$(apt-get "${apt_options[@]}" source --print-uris "qemu=$source_version" 2>/dev/null |
    grep "\.orig\.tar\." | head -n 1) || return 1
  uri=$(awk '{print $1}' <<<"$line" | tr -d "'")
  sum=$(grep -o 'SHA256:[0-9a-f]*' <<<"$line" | cut -d: -f2)
  [[ -n $uri && -n $sum ]] || return 1
  echo "fetching $uri" >&2
  curl -sSfL -o "$tmp/orig.tar" "$uri" || return 1
  echo "$sum  $tmp/orig.tar" | sha256sum -c --quiet || return 1
  tar -xf "$tmp/orig.tar" -C "$tmp" --wildcards '*/include/qemu/qemu-plugin.h' || return 1
  mkdir -p "$cache"
  cp "$tmp"/*/include/qemu/qemu-plugin.h "$header"
}
if [[ ! -f $header ]]; then
  fetch_header || die "cannot fetch qemu-plugin.h from Debian's qemu $source_version source: no instruction counts" 3
fi
plugin=$cache/libinsn_count.so
if [[ ! -f $plugin || $here/insn_count.c -nt $plugin ]]; then
  cc -std=c11 -O2 -Wall -Wextra -Werror -shared -fPIC -I"$cache" "$here/insn_count.c" -o "$plugin"
fi

# The target's loader and libraries, as .ci/cross-build.sh picks them.
root=/usr/aarch64-linux-gnu
[[ -f /usr/lib/aarch64-linux-gnu/libc.so.6 ]] && root=/

tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
count() {  # level repeat frame -> "total thread0 thread1 ..." of the whole run
  local plugin_args=$plugin,outfile=$tmp/n
  ((threads > 1)) && plugin_args+=,threads=on
  KG_SIMD=$1 qemu-aarch64 -L "$root" -plugin "$plugin_args" "$keygraph" bench \
    --index "$index" --repeat "$2" --threads "$threads" ${KG_BENCH_ARGS:-} "$3" >"$tmp/out" 2>&1 ||
    die "$keygraph bench failed: $(tail -n 3 "$tmp/out")"
  awk '/^instructions/ {total = $2} /^thread/ {t = t " " $3} END {print total t}' "$tmp/n"
}
echo "keygraph: $keygraph"
echo "index: $index; qemu: $(qemu-aarch64 --version | head -n 1); --threads $threads ${KG_BENCH_ARGS:-}"
printf '%-24s %-7s %14s %s  %s\n' frame KG_SIMD "insns/frame" \
  "$( ((threads > 1)) && echo " busiest thread")" "bench's result"
for frame in "$@"; do
  for level in $levels; do
    read -r -a first <<<"$(count "$level" "$r1" "$frame")"
    read -r -a second <<<"$(count "$level" "$r2" "$frame")"
    found=$(grep -o '[0-9]* detection(s)[^;]*;[^;]*keypoints' "$tmp/out" | head -n 1 || true)
    total=$(((second[0] - first[0]) / (r2 - r1)))
    busiest=""
    if ((threads > 1)); then
      most=0
      for ((i = 1; i < ${#second[@]}; ++i)); do
        d=$(((second[i] - ${first[i]:-0}) / (r2 - r1)))
        ((d > most)) && most=$d
      done
      busiest=$(printf ' %14d (%.2fx)' "$most" "$(awk -v t="$total" -v m="$most" 'BEGIN {print t / m}')")
    fi
    printf '%-24s %-7s %14d%s  %s\n' "$(basename "$frame")" "$level" "$total" "$busiest" "$found"
  done
done
