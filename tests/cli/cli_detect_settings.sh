#!/bin/bash
# Runtime options of the commands that detect (issues 34 and 35), on real
# images: --threads N and --set NAME=VALUE on detect, live, bench and eval
# (--truth, its keygraph method, with --index and with --models).
#   --threads       detect --json and live --json give the same lines for 1
#                   and 2 threads (times aside); bench says its thread count
#   --set           time_budget_ms=0.001 stops early without an error (the
#                   stage named in the stats, fewer detections), also on a
#                   frame larger than 640x480, for which the detector is made
#                   again (the options kept); min_confidence=1.01 is out of
#                   range; a parameter fixed by the index, an unknown name, a
#                   bad value: one error line, exit 2, the unknown name's
#                   line naming the runtime options
#
# usage: cli_detect_settings.sh KEYGRAPH OPENCV_DATA_DIR KG_TO_PGM
set -u

KG=${1:?usage: cli_detect_settings.sh KEYGRAPH OPENCV_DATA_DIR KG_TO_PGM}
DATA=${2:?}
TO_PGM=${3:?}

TEST_NAME=cli_detect_settings
. "$(dirname "$0")/test_support.sh"
# The JSON lines of $OUT without their times.
untimed() { sed 's/"time_ms": [0-9.e+-]*, //' "$OUT"; }

INDEX=$WORK/box.kgi
"$KG" build -q --no-look-alikes "$DATA/box.png" -o "$INDEX" >/dev/null 2>"$ERR" || {
  echo "cli_detect_settings: cannot build box.kgi: $(cat "$ERR")" >&2
  exit 1
}
SCENES=("$DATA/box_in_scene.png" "$DATA/box.png" "$DATA/graf3.png")
FRAMES=$WORK/frames
mkdir "$FRAMES"
"$TO_PGM" "$DATA/box_in_scene.png" "$FRAMES/1_scene.pgm" &&
  "$TO_PGM" "$DATA/graf3.png" "$FRAMES/2_graf.pgm" || exit 1

# --- --threads: the same detections for 1 and 2 threads ------------------------------
run "$KG" detect --index "$INDEX" --json --threads 1 "${SCENES[@]}"
untimed >"$WORK/one.jsonl"
[ "$rc" -eq 0 ] && [ "$(wc -l <"$WORK/one.jsonl")" -eq 3 ] || bad "detect --threads 1: exit $rc: $(cat "$ERR")"
grep -q '"model": "box"' "$WORK/one.jsonl" || bad "detect --threads 1 finds no box"
run "$KG" detect --index "$INDEX" --json --threads 2 "${SCENES[@]}"
untimed >"$WORK/two.jsonl"
[ "$rc" -eq 0 ] || bad "detect --threads 2: exit $rc: $(cat "$ERR")"
cmp -s "$WORK/one.jsonl" "$WORK/two.jsonl" ||
  bad "detect --json: --threads 2 differs from --threads 1: $(diff "$WORK/one.jsonl" "$WORK/two.jsonl" | head -c 600)"
run "$KG" live --index "$INDEX" --images "$FRAMES" --json -q --threads 1
untimed >"$WORK/live1.jsonl"
run "$KG" live --index "$INDEX" --images "$FRAMES" --json -q --threads 2
untimed >"$WORK/live2.jsonl"
[ "$rc" -eq 0 ] && [ "$(wc -l <"$WORK/live2.jsonl")" -eq 2 ] &&
  cmp -s "$WORK/live1.jsonl" "$WORK/live2.jsonl" ||
  bad "live --json: --threads 2 differs from --threads 1 (exit $rc): $(cat "$ERR")"
run "$KG" bench --index "$INDEX" --repeat 2 --json --threads 2 "$FRAMES/1_scene.pgm"
grep -q '"threads": 2, ' "$OUT" && grep -q '"detections": {"min": 1, "max": 1}' "$OUT" ||
  bad "bench --threads 2: the thread count and the box in every run: $(cat "$OUT" "$ERR")"
run "$KG" bench --index "$INDEX" --repeat 1 --threads 2 "$FRAMES/1_scene.pgm"
grep -q '2 threads$' "$OUT" || bad "bench --threads 2: the text says so: $(head -n 1 "$OUT")"

# --- --set time_budget_ms: stopped early, no error -----------------------------------
# box_in_scene (512x384) within the default workspace; graf3 (800x640) and
# its PGM make the detector again, larger, which must keep the budget.
run "$KG" detect --index "$INDEX" --json --set time_budget_ms=0.001 "${SCENES[0]}" "${SCENES[2]}"
if [ "$rc" -ne 0 ] || [ -s "$ERR" ] ||
  [ "$(grep -c '"stopped_early": "[a-z]*"' "$OUT")" -ne 2 ] || grep -q '"model": "box"' "$OUT"; then
  bad "detect --set time_budget_ms=0.001: exit $rc, stopped early on both, nothing found: $(cat "$OUT" "$ERR" | head -c 800)"
fi
grep -c '"stopped_early": null' "$WORK/one.jsonl" | grep -qx 3 ||
  bad "detect without a budget: stopped_early null on every scene"
run "$KG" detect --index "$INDEX" --set time_budget_ms=0.001 "${SCENES[0]}"
[ "$rc" -eq 0 ] && grep -q "0 detection(s) in .* (stopped early: time budget spent in the " "$OUT" ||
  bad "detect text: the stop said: $(cat "$OUT" "$ERR")"
for cmd in "live --images $FRAMES --json --no-track" "bench --json --repeat 1 $FRAMES"; do
  # shellcheck disable=SC2086
  run "$KG" $cmd --index "$INDEX" --set time_budget_ms=0.001
  [ "$rc" -eq 0 ] && [ "$(wc -l <"$OUT")" -eq 2 ] || bad "$cmd with a budget: exit $rc: $(cat "$ERR")"
done
run "$KG" live --index "$INDEX" --images "$FRAMES" --json --no-track --set time_budget_ms=0.001
[ "$(grep -c '"stopped_early": "[a-z]*"' "$OUT")" -eq 2 ] ||
  bad "live --set time_budget_ms=0.001: both frames stopped early (the larger one too)"
run "$KG" bench --index "$INDEX" --json --repeat 1 --set time_budget_ms=0.001 "$FRAMES"
grep -c '"detections": {"min": 0, "max": 0}' "$OUT" | grep -qx 2 ||
  bad "bench --set time_budget_ms=0.001: nothing found within the budget: $(cat "$OUT")"

# --- bad --set and --threads: one line, exit 2 ---------------------------------------
SCENE=${SCENES[0]}
for cmd in "detect $SCENE" "live --images $FRAMES" "bench $SCENE"; do
  name=${cmd%% *}
  # shellcheck disable=SC2086
  run "$KG" $cmd --index "$INDEX" --set bogus=1
  one_error 2 "--set bogus=1: unknown option 'bogus'" && grep -q "min_confidence" "$ERR" &&
    grep -q "time_budget_ms" "$ERR" && grep -q "ransac.seed" "$ERR" ||
    bad "$name --set bogus=1: one line naming the runtime options, exit 2 (exit $rc): $(cat "$ERR")"
  # shellcheck disable=SC2086
  run "$KG" $cmd --index "$INDEX" --set keypoints.hessian_octaves=2
  one_error 2 "keypoints.hessian_octaves is fixed by the index" ||
    bad "$name --set of an index parameter: exit $rc: $(cat "$ERR")"
  # shellcheck disable=SC2086
  run "$KG" $cmd --index "$INDEX" --set ransac.seed=abc
  one_error 2 "bad value 'abc' for ransac.seed" || bad "$name --set ransac.seed=abc: exit $rc: $(cat "$ERR")"
  # shellcheck disable=SC2086
  run "$KG" $cmd --index "$INDEX" --set min_confidence=1.01
  one_error 2 "min_confidence must be in [0, 1]" ||
    bad "$name --set min_confidence=1.01: exit $rc: $(cat "$ERR")"
  # shellcheck disable=SC2086
  run "$KG" $cmd --index "$INDEX" --set min_confidence
  one_error 2 "takes NAME=VALUE" || bad "$name --set without '=': exit $rc: $(cat "$ERR")"
  for n in 0 65 two; do
    # shellcheck disable=SC2086
    run "$KG" $cmd --index "$INDEX" --threads $n
    one_error 2 "--threads $n" || bad "$name --threads $n: exit $rc: $(cat "$ERR")"
  done
  [ -s "$OUT" ] && bad "$name: a usage error wrote to stdout: $(head -c 300 "$OUT")"
done
# Repeated --set: each applies, the last one of a name wins.
run "$KG" detect --index "$INDEX" --json --set time_budget_ms=0.001 --set time_budget_ms=0 "$SCENE"
untimed | cmp -s - <(sed -n 1p "$WORK/one.jsonl") ||
  bad "--set repeated: the last value of a name wins: $(cat "$ERR")"

# --- eval --truth: the keygraph method's --threads and --set -------------------------
MANIFEST=$WORK/truth.jsonl
{
  echo "{\"scene\": \"$DATA/box_in_scene.png\", \"instances\": [{\"model\": \"box\", \"corners\": [[118, 161], [284, 175], [268, 298], [90, 272]]}]}"
  echo "{\"scene\": \"$DATA/baboon.jpg\", \"instances\": []}"
} >"$MANIFEST"
# The "found" count of eval's keygraph row in $OUT.
found() { awk '$1 == "keygraph" { print $3; exit }' "$OUT"; }
for n in 1 2; do
  run "$KG" eval --truth "$MANIFEST" --index "$INDEX" -q --threads $n -o "$WORK/eval$n"
  [ "$rc" -eq 0 ] && [ "$(found)" = 1 ] || bad "eval --threads $n: exit $rc, found $(found): $(cat "$ERR")"
done
cmp -s "$WORK/eval1/truth-detections.csv" "$WORK/eval2/truth-detections.csv" ||
  bad "eval --truth: --threads 2 detections differ from --threads 1"
run "$KG" eval --truth "$MANIFEST" --index "$INDEX" -q --set time_budget_ms=0.001
[ "$rc" -eq 0 ] && [ "$(found)" = 0 ] ||
  bad "eval --index --set time_budget_ms=0.001: exit $rc, found $(found) (expected 0): $(cat "$ERR")"
mkdir "$WORK/models"
cp "$DATA/box.png" "$WORK/models/"
run "$KG" eval --truth "$MANIFEST" --models "$WORK/models" -q --set views.max_tilt=0 --threads 2
[ "$rc" -eq 0 ] && [ "$(found)" = 1 ] ||
  bad "eval --models --threads 2: exit $rc, found $(found) (expected 1): $(cat "$ERR")"
run "$KG" eval --truth "$MANIFEST" --models "$WORK/models" -q --set views.max_tilt=0 \
  --set time_budget_ms=0.001
[ "$rc" -eq 0 ] && [ "$(found)" = 0 ] ||
  bad "eval --models --set time_budget_ms=0.001: exit $rc, found $(found) (expected 0): $(cat "$ERR")"
run "$KG" eval --truth "$MANIFEST" --index "$INDEX" -q --set min_confidence=2
one_error 2 "min_confidence must be in [0, 1]" || bad "eval --set min_confidence=2: exit $rc: $(cat "$ERR")"
run "$KG" eval --truth "$MANIFEST" --index "$INDEX" -q --set bogus=1
one_error 2 "--set bogus=1: unknown option 'bogus'" && grep -q "time_budget_ms" "$ERR" ||
  bad "eval --set bogus=1: exit $rc: $(cat "$ERR")"
run "$KG" eval --truth "$MANIFEST" --index "$INDEX" -q --threads 0
one_error 2 "--threads 0" || bad "eval --threads 0: exit $rc: $(cat "$ERR")"

finish
