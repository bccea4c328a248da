#!/bin/sh
# keygraph manifest and keygraph eval --truth end to end on a few images of
# each real photo set in $KG_DATA_DIR/real (its README.md):
#   exit signs: the manifest keeps 105 signs, dev and test split them; the
#     frame model-exit-left.png was cropped from plus 3 test frames;
#   planar pairs: adam and city, each searched with its own model;
#   negatives: 4 photos searched with the exit-sign models.
# Registered only when the sets are there (tests/CMakeLists.txt); fails with
# the reason when they have gone since.
#
# usage: cli_eval_truth_real.sh PATH/TO/keygraph DATA_DIR
# (the environment's KG_DATA_DIR, when set, overrides DATA_DIR, as for the
# other tests that read the data sets)
set -u
KG=${1:?usage: cli_eval_truth_real.sh KEYGRAPH_BINARY DATA_DIR}
DATA_DIR=${KG_DATA_DIR:-${2:?usage: cli_eval_truth_real.sh KEYGRAPH_BINARY DATA_DIR}}
REAL=$DATA_DIR/real
for d in exit-signs planar-pairs negatives; do
  if [ ! -d "$REAL/$d" ]; then
    echo "needs data: no directory $REAL/$d; set KG_DATA_DIR to the directory that holds real/ (README: Test data)"
    exit 1
  fi
done
[ -x "$KG" ] || { echo "no keygraph binary at $KG" >&2; exit 1; }
command -v python3 >/dev/null 2>&1 || { echo "python3 is needed to read JSON" >&2; exit 1; }
WORK=$(mktemp -d "${TMPDIR:-/tmp}/kg_truth_real.XXXXXX") || exit 1
trap 'rm -rf "$WORK"' EXIT
failures=0
bad() {
  echo "FAIL: $*" >&2
  failures=$((failures + 1))
}
# summary FILE METHOD FIELD: one number of truth-summary.json.
summary() {
  python3 -c 'import json,sys; r={x["method"]: x for x in json.load(open(sys.argv[1]))["results"]}; print(r[sys.argv[2]][sys.argv[3]])' "$@"
}

# Exit signs: the manifests, the split.
M=$WORK/manifests
mkdir -p "$M"
"$KG" manifest exit-signs "$REAL/exit-signs" -o "$M/exit.jsonl" >"$WORK/all.txt" ||
  bad "manifest exit-signs failed"
"$KG" manifest exit-signs "$REAL/exit-signs" -o "$M/dev.jsonl" --split dev >"$WORK/dev.txt" ||
  bad "manifest exit-signs --split dev failed"
"$KG" manifest exit-signs "$REAL/exit-signs" -o "$M/test.jsonl" --split test >/dev/null ||
  bad "manifest exit-signs --split test failed"
[ "$(wc -l <"$M/exit.jsonl")" -eq 105 ] || bad "exit-signs: $(wc -l <"$M/exit.jsonl") scenes, expected 105"
grep -q '105 frames (105 signs) kept, 18 within 30 s' "$WORK/all.txt" ||
  bad "exit-signs summary: $(cat "$WORK/all.txt")"
dev=$(wc -l <"$M/dev.jsonl")
test=$(wc -l <"$M/test.jsonl")
[ $((dev + test)) -eq 105 ] || bad "dev $dev + test $test scenes is not 105"
[ "$(sort "$M/dev.jsonl" "$M/test.jsonl" | uniq -d | wc -l)" -eq 0 ] || bad "dev and test share scenes"
grep -q "dev $dev frames" "$WORK/dev.txt" || bad "the printed dev count is not $dev: $(cat "$WORK/dev.txt")"
grep -q '263548\.\|264818\.' "$M/exit.jsonl" && bad "a model's source frame is in the manifest"
[ -f "$M/exit-sign-models.json" ] || bad "no exit-sign-models.json"
# Paths are relative to the manifest: the images are used in place.
grep -q '"scene":"\.\./' "$M/exit.jsonl" || bad "scene paths are not relative to the manifest"

# The model's own source frame (left out of the manifests) and 3 test frames:
# SIFT finds the sign it was cropped from, and nothing in the others.
awk '$1 ~ /263548\.696465416/ {printf "{\"scene\": \"%s/%s\", \"instances\": [{\"model\": [\"exit-left\", \"exit-right\"], \"corners\": [[%s, %s], [%s, %s], [%s, %s], [%s, %s]]}]}\n", dir, $1, $3, $4, $5, $6, $7, $8, $9, $10}' \
  dir="$REAL/exit-signs" "$REAL/exit-signs/corners.txt" >"$M/few-exit.jsonl"
head -n 3 "$M/test.jsonl" >>"$M/few-exit.jsonl"
"$KG" eval --truth "$M/few-exit.jsonl" --models "$M/exit-sign-models.json" \
  --methods keygraph,sift-magsac --out "$WORK/exit" >"$WORK/stdout" 2>"$WORK/stderr" ||
  bad "eval exit signs failed: $(cat "$WORK/stderr")"
[ "$(summary "$WORK/exit/truth-summary.json" sift-magsac instances)" = 4 ] || bad "exit: not 4 instances"
[ "$(summary "$WORK/exit/truth-summary.json" sift-magsac found)" = 1 ] ||
  bad "exit: sift-magsac did not find exactly the model's own sign: $(cat "$WORK/stdout")"
grep -q '^sift-magsac,0,1,.*263548\.696465416\.jpg,exit-left,true,0,' "$WORK/exit/truth-detections.csv" ||
  bad "exit: no true exit-left detection in the model's source frame"

# The ground truth asked of the keypoints (issue 38): a 25 px dev sign whose
# true pose re-finds 6-7 model keypoints is confirmable by the small-instance
# rule (ransac.small_*) and not without it; and with the frame upsampled
# (keypoints.scene_upsample=2) the support is measured on the upsampled
# frame's keypoints: a 50 px dev sign found that way has its true pose
# confirmed and enough correct correspondences.
grep -e '263825\.903275125' "$M/dev.jsonl" >"$M/small.jsonl"
grep -e '264907\.562212375' "$M/dev.jsonl" >"$M/up.jsonl"
[ "$(wc -l <"$M/small.jsonl")" -eq 1 ] && [ "$(wc -l <"$M/up.jsonl")" -eq 1 ] ||
  bad "the two dev frames are not in the dev manifest"
# case FILE FIELD: one field of the only case of truth-cases.csv.
case_field() {
  python3 -c 'import csv,sys; print(next(csv.DictReader(open(sys.argv[1])))[sys.argv[2]])' "$@"
}
for rule in on off; do
  set -- 
  [ $rule = off ] && set -- --set ransac.small_max_size=0
  "$KG" eval --truth "$M/small.jsonl" --models "$M/exit-sign-models.json" --methods keygraph \
    --out "$WORK/small-$rule" "$@" >"$WORK/stdout" 2>"$WORK/stderr" ||
    bad "eval small sign ($rule) failed: $(cat "$WORK/stderr")"
done
r=$(case_field "$WORK/small-on/truth-cases.csv" truth_refound)
[ "$r" -ge 6 ] && [ "$r" -lt 8 ] || bad "small sign: $r model keypoints re-found, expected 6 or 7"
[ "$(case_field "$WORK/small-on/truth-cases.csv" truth_verifiable)" = 1 ] ||
  bad "small sign: not confirmable with the small-instance rule"
[ "$(case_field "$WORK/small-off/truth-cases.csv" truth_verifiable)" = 0 ] ||
  bad "small sign: confirmable without the small-instance rule"
"$KG" eval --truth "$M/up.jsonl" --models "$M/exit-sign-models.json" --methods keygraph \
  --set keypoints.scene_upsample=2 --out "$WORK/up" >"$WORK/stdout" 2>"$WORK/stderr" ||
  bad "eval upsampled failed: $(cat "$WORK/stderr")"
[ "$(case_field "$WORK/up/truth-cases.csv" found)" = 1 ] || bad "upsampled: the 50 px sign not found"
[ "$(case_field "$WORK/up/truth-cases.csv" truth_refound)" -ge 12 ] ||
  bad "upsampled: the true pose not measured or re-finds under 12 keypoints"
[ "$(case_field "$WORK/up/truth-cases.csv" truth_verifiable)" = 1 ] || bad "upsampled: not confirmable"
[ "$(case_field "$WORK/up/truth-cases.csv" truth_matches)" -ge 3 ] ||
  bad "upsampled: fewer than 3 correct correspondences at the true pose"

# Planar pairs: adam and city with their own models only.
"$KG" manifest planar-pairs "$REAL/planar-pairs" -o "$M/pairs.jsonl" >/dev/null ||
  bad "manifest planar-pairs failed"
[ "$(wc -l <"$M/pairs.jsonl")" -eq 14 ] || bad "planar-pairs: expected 14 scenes"
grep -e '"search":\["adam"\]' -e '"search":\["city"\]' "$M/pairs.jsonl" >"$M/few-pairs.jsonl"
"$KG" eval --truth "$M/few-pairs.jsonl" --models "$M/planar-pair-models.json" \
  --methods keygraph,sift-magsac --out "$WORK/pairs" >"$WORK/stdout" 2>"$WORK/stderr" ||
  bad "eval planar pairs failed: $(cat "$WORK/stderr")"
[ "$(summary "$WORK/pairs/truth-summary.json" sift-magsac homography_within_2px)" = 2 ] ||
  bad "pairs: sift-magsac not within 2 px on adam and city: $(cat "$WORK/stdout")"
awk -F, '$1 == "keygraph" && $4 ~ /adamB/ && $13 >= 0 && $13 <= 2 {ok = 1} END {exit !ok}' \
  "$WORK/pairs/truth-cases.csv" || bad "pairs: keygraph not within 2 px on adam: $(cat "$WORK/stdout")"

# Negatives: 4 photos, exit-sign models, no detection.
"$KG" manifest negatives "$REAL/negatives" -o "$M/neg.jsonl" >/dev/null || bad "manifest negatives failed"
[ "$(wc -l <"$M/neg.jsonl")" -eq 247 ] || bad "negatives: expected 247 scenes"
head -n 4 "$M/neg.jsonl" >"$M/few-neg.jsonl"
"$KG" eval --truth "$M/few-neg.jsonl" --models "$M/exit-sign-models.json" \
  --methods keygraph,sift-magsac --out "$WORK/neg" >"$WORK/stdout" 2>"$WORK/stderr" ||
  bad "eval negatives failed: $(cat "$WORK/stderr")"
for m in keygraph sift-magsac; do
  [ "$(summary "$WORK/neg/truth-summary.json" $m scenes_without_instances)" = 4 ] ||
    bad "negatives: $m did not see 4 scenes without instances"
  [ "$(summary "$WORK/neg/truth-summary.json" $m false_detections)" = 0 ] ||
    bad "negatives: $m detected an exit sign: $(cat "$WORK/stdout")"
done

if [ $failures -ne 0 ]; then
  echo "$failures failure(s)" >&2
  exit 1
fi
echo "cli_eval_truth_real: all checks passed"
