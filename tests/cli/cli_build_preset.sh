#!/bin/bash
# keygraph build --preset defaults|frontal|angled (issue 34: a named preset
# instead of a chain of --set flags), on opencv-doc's box.png:
#   each preset       the same index, byte for byte, as the options it names
#                     spelled out (the chains docs/RESULTS.md gives)
#   over the preset   --set and the other options apply over it, given
#                     before or after it
#   bad presets       one error line naming the known ones, exit 2, no index
#
# usage: cli_build_preset.sh KEYGRAPH OPENCV_DATA_DIR [sanitized]
#   sanitized (a sanitizer build, where the angled preset's 2 tilt levels
#   of box.png take 16 s of CPU a build): every build scales box.png to 160
#   px on its long edge (--max-side 160, a 4th of the pixels); the same
#   checks on a smaller model
set -u

KG=${1:?usage: cli_build_preset.sh KEYGRAPH OPENCV_DATA_DIR [sanitized]}
DATA=${2:?}
MODEL=$DATA/box.png
SIZE=()
[ "${3:-}" = sanitized ] && SIZE=(--max-side 160)

TEST_NAME=cli_build_preset
. "$(dirname "$0")/test_support.sh"
# build OUT ARGS...: a quick build of box.png into $WORK/OUT.kgi.
build() {
  local out=$1
  shift
  "$KG" build -q --no-look-alikes ${SIZE[@]+"${SIZE[@]}"} "$@" "$MODEL" -o "$WORK/$out.kgi" >/dev/null 2>"$ERR" ||
    bad "build $*: exit $?: $(cat "$ERR")"
}
# param INDEX NAME: the value inspect prints for parameter NAME.
param() { "$KG" inspect "$WORK/$1.kgi" | awk -v n="$2" '$1 == n { print $2 }'; }
same() { cmp -s "$WORK/$1.kgi" "$WORK/$2.kgi" || bad "$3: $1.kgi and $2.kgi differ"; }

# --- each preset is the options it names --------------------------------------------
FRONTAL=(--max-tilt 0 --set ransac.min_triangle_correlation=0 --set graph.complete_circuits=0
  --set graph.max_neighbour_rank=0 --set descriptor.max_search_leaves=20)
ANGLED=(--max-tilt 60 --set ransac.min_triangle_correlation=0.6 --set graph.complete_circuits=1
  --set graph.max_neighbour_rank=0 --set descriptor.max_search_leaves=10)
build frontal --preset frontal
build frontal_spelled "${FRONTAL[@]}"
same frontal frontal_spelled "--preset frontal is not the frontal options spelled out"
build angled --preset angled
build angled_spelled "${ANGLED[@]}"
same angled angled_spelled "--preset angled is not the angled options spelled out"
[ "$(param angled views.tilt_levels)" = 2 ] && [ "$(param angled views.max_tilt)" = 60 ] ||
  bad "--preset angled: views.tilt_levels $(param angled views.tilt_levels), max_tilt $(param angled views.max_tilt)"
build defaults --preset defaults
build plain
same defaults plain "--preset defaults is not the defaults"
cmp -s "$WORK/frontal.kgi" "$WORK/plain.kgi" && bad "--preset frontal gave the default index"

# --- other options apply over the preset, before or after it -------------------------
build leaves_after --preset frontal --set descriptor.max_search_leaves=7
build leaves_before --set descriptor.max_search_leaves=7 --preset frontal
same leaves_after leaves_before "--set before and after --preset"
for i in leaves_after leaves_before; do
  [ "$(param $i descriptor.max_search_leaves)" = 7 ] && [ "$(param $i graph.complete_circuits)" = 0 ] &&
    [ "$(param $i views.max_tilt)" = 0 ] ||
    bad "$i: --set over --preset frontal: leaves $(param $i descriptor.max_search_leaves), completion $(param $i graph.complete_circuits), tilt $(param $i views.max_tilt)"
done
build tilt_over --max-tilt 30 --preset angled
[ "$(param tilt_over views.max_tilt)" = 30 ] && [ "$(param tilt_over views.tilt_levels)" = 1 ] &&
  [ "$(param tilt_over descriptor.max_search_leaves)" = 10 ] ||
  bad "--max-tilt 30 over --preset angled: tilt $(param tilt_over views.max_tilt) in $(param tilt_over views.tilt_levels) levels"

# --- bad presets: one line, exit 2, nothing written ----------------------------------
for args in "--preset sideways" "--preset" "--preset frontal --preset angled"; do
  # shellcheck disable=SC2086
  "$KG" build $args "$MODEL" -o "$WORK/bad.kgi" >"$WORK/stdout" 2>"$ERR"
  rc=$?
  [ "$rc" -eq 2 ] && [ "$(wc -l <"$ERR")" -eq 1 ] && [ ! -e "$WORK/bad.kgi" ] ||
    bad "build $args: exit $rc, one error line, no index: $(cat "$ERR")"
done
"$KG" build --preset sideways "$MODEL" -o "$WORK/bad.kgi" 2>"$ERR" >/dev/null
grep -qF "keygraph: build: --preset sideways: unknown preset 'sideways' (defaults, frontal or angled)" "$ERR" ||
  bad "an unknown preset names the known ones: $(cat "$ERR")"
"$KG" build --help | grep -q -- "--preset NAME" || bad "build --help lacks --preset"

finish
