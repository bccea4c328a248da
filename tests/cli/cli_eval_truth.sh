#!/bin/sh
# keygraph eval --truth on bad input -- a manifest line that does not parse,
# an unknown model, a missing scene, corners that are not four points, bad
# options: one line on stderr naming the file and line, a non-zero exit and
# nothing written into --out -- and a small run end to end on opencv-doc
# images: box in box_in_scene (corners), graf1 in graf3 (the homography
# H1to3p) and baboon (no model), with every output file checked.
#
# usage: cli_eval_truth.sh PATH/TO/keygraph OPENCV_DATA_DIR
set -u
KG=${1:?usage: cli_eval_truth.sh KEYGRAPH_BINARY OPENCV_DATA_DIR}
DATA=${2:?usage: cli_eval_truth.sh KEYGRAPH_BINARY OPENCV_DATA_DIR}
[ -x "$KG" ] || { echo "no keygraph binary at $KG" >&2; exit 1; }
for f in box.png box_in_scene.png graf1.png graf3.png baboon.jpg; do
  [ -f "$DATA/$f" ] || { echo "missing $DATA/$f (install Debian's opencv-doc package)" >&2; exit 1; }
done
command -v python3 >/dev/null 2>&1 || { echo "python3 is needed to validate JSON" >&2; exit 1; }
KG=$(cd "$(dirname "$KG")" && pwd)/$(basename "$KG")
DATA=$(cd "$DATA" && pwd)
TEST_NAME=cli_eval_truth
. "$(dirname "$0")/test_support.sh"

# expect_failure NAME PATTERN CMD...: one stderr line matching PATTERN, a
# non-zero exit, and no new files in $WORK/case (the commands write --out there).
expect_failure() {
  name=$1
  pattern=$2
  shift 2
  rm -rf "$WORK/case" && mkdir "$WORK/case"
  (cd "$WORK/case" && "$@") >"$WORK/stdout" 2>"$WORK/stderr"
  rc=$?
  [ $rc -ne 0 ] || bad "$name: exit code 0"
  [ $rc -lt 128 ] || bad "$name: crashed (exit $rc)"
  lines=$(wc -l <"$WORK/stderr")
  [ "$lines" -eq 1 ] || bad "$name: $lines lines on stderr: $(cat "$WORK/stderr")"
  grep -q '^keygraph: ' "$WORK/stderr" || bad "$name: message does not start with 'keygraph: '"
  grep -q -- "$pattern" "$WORK/stderr" || bad "$name: no '$pattern' in: $(cat "$WORK/stderr")"
  [ -z "$(ls -A "$WORK/case")" ] || bad "$name: left files behind: $(ls -A "$WORK/case")"
}

# Models: a directory of images named by their stems.
mkdir -p "$WORK/models" "$WORK/set"
cp "$DATA/box.png" "$DATA/graf1.png" "$WORK/models/"
M="$WORK/set/m.jsonl"
BOX='[[0, 0], [323, 0], [323, 222], [0, 222]]'  # any simple quadrilateral will do for errors
good_line() { echo "{\"scene\": \"$DATA/baboon.jpg\", \"instances\": []}"; }

{ good_line; echo '{"scene": "x.png", "instances": [}'; } >"$M"
expect_failure "line that does not parse" "m.jsonl:2: not valid JSON" \
  "$KG" eval --truth "$M" --models "$WORK/models" --methods keygraph --out out
{ good_line; good_line; echo "{\"scene\": \"$DATA/box_in_scene.png\", \"instances\": [{\"model\": \"nosuch\", \"corners\": $BOX}]}"; } >"$M"
expect_failure "unknown model" 'm.jsonl:3: unknown model "nosuch"' \
  "$KG" eval --truth "$M" --models "$WORK/models" --methods keygraph --out out
echo '{"scene": "absent.png", "instances": []}' >"$M"
expect_failure "missing scene" "m.jsonl:1: scene .*absent.png: no such file" \
  "$KG" eval --truth "$M" --models "$WORK/models" --methods keygraph --out out
echo "{\"scene\": \"$DATA/box_in_scene.png\", \"instances\": [{\"model\": \"box\", \"corners\": [[0, 0], [1, 0], [1, 1]]}]}" >"$M"
expect_failure "three corners" "m.jsonl:1: \"corners\" must be four" \
  "$KG" eval --truth "$M" --models "$WORK/models" --methods keygraph --out out
echo "{\"scene\": \"$DATA/box_in_scene.png\", \"instances\": [{\"model\": \"box\", \"corners\": [[0, 0], [9, 9], [9, 0], [0, 9]]}]}" >"$M"
expect_failure "crossed corners" "m.jsonl:1: \"corners\" cross" \
  "$KG" eval --truth "$M" --models "$WORK/models" --methods keygraph --out out
good_line >"$M"
expect_failure "no models" "give one of --models" "$KG" eval --truth "$M" --out out
expect_failure "missing models" "nomodels: no such" \
  "$KG" eval --truth "$M" --models "$WORK/nomodels" --out out
expect_failure "missing manifest" "none.jsonl: no such file" \
  "$KG" eval --truth "$WORK/none.jsonl" --models "$WORK/models" --out out
expect_failure "unknown method" "unknown method 'nonesuch'" \
  "$KG" eval --truth "$M" --models "$WORK/models" --methods keygraph,nonesuch --out out
expect_failure "bad tolerance" "--tolerance" \
  "$KG" eval --truth "$M" --models "$WORK/models" --tolerance -3 --out out
expect_failure "bad --set" "eval: " \
  "$KG" eval --truth "$M" --models "$WORK/models" --set nosuch.param=1 --out out
expect_failure "unknown option" "unknown option --bogus" \
  "$KG" eval --truth "$M" --models "$WORK/models" --bogus 1
echo '{"box": "box.png", "graf1": "nosuch.png"}' >"$WORK/models/models.json"
expect_failure "models.json names a missing file" "nosuch.png" \
  "$KG" eval --truth "$M" --models "$WORK/models" --methods keygraph --out out
echo '{"box": {"file": "box.png", "roi": [0, 0, 9999, 10]}}' >"$WORK/models/models.json"
expect_failure "models.json ROI outside" "lies outside" \
  "$KG" eval --truth "$M" --models "$WORK/models" --methods keygraph --out out
echo '{"box": ' >"$WORK/models/models.json"
expect_failure "models.json not JSON" "models.json: not valid JSON" \
  "$KG" eval --truth "$M" --models "$WORK/models" --methods keygraph --out out
rm "$WORK/models/models.json"
"$KG" build "$WORK/models/box.png" -o "$WORK/box.kgi" >/dev/null || bad "build box.kgi failed"
expect_failure "baseline with an index" "needs the model images" \
  "$KG" eval --truth "$M" --index "$WORK/box.kgi" --methods sift-magsac --out out
expect_failure "--set with an index" "keeps its own parameters" \
  "$KG" eval --truth "$M" --index "$WORK/box.kgi" --methods keygraph \
  --set graph.max_anisotropy=2.5 --out out
touch "$WORK/case-file"
expect_failure "--out is a file" "not a directory" \
  "$KG" eval --truth "$M" --models "$WORK/models" --out "$WORK/case-file"
expect_failure "manifest: unknown set" "unknown set" "$KG" manifest nosuch "$WORK" -o out.jsonl
expect_failure "manifest: not the set's directory" "corners.txt: not found" \
  "$KG" manifest exit-signs "$WORK" -o out.jsonl
expect_failure "manifest: bad split" "dev, test or model-bursts" \
  "$KG" manifest exit-signs "$WORK" -o out.jsonl --split train

# End to end: box (corners, clicked from the bottom left anticlockwise), graf1
# in graf3 (homography), baboon (none of them); models from models.json with
# paths relative to it (graf through an ROI: the whole image).
H=$(python3 - "$DATA/H1to3p.xml" <<'PY'
import re, sys
text = open(sys.argv[1]).read()
print(", ".join(re.search(r"<data>(.*)</data>", text, re.S).group(1).split()))
PY
)
printf '{"box": "box.png", "graf": {"file": "graf1.png", "roi": [0, 0, 800, 640]}}\n' >"$WORK/models/models.json"
mkdir -p "$WORK/set/frames"
cp "$DATA/box_in_scene.png" "$DATA/graf3.png" "$WORK/set/frames/"
cat >"$M" <<EOF2
# box_in_scene: the corners all four methods agree on to 3 px, bottom left first, anticlockwise
{"scene": "frames/box_in_scene.png", "instances": [{"model": ["box"], "corners": [[90, 272], [268, 298], [284, 175], [118, 161]]}]}
{"scene": "frames/graf3.png", "search": ["graf"], "instances": [{"model": "graf", "homography": [$H]}]}
{"scene": "$DATA/baboon.jpg", "instances": []}
EOF2
"$KG" eval --truth "$M" --models "$WORK/models" --methods keygraph,sift-magsac \
  --out "$WORK/out" --gallery >"$WORK/stdout" 2>"$WORK/stderr" ||
  bad "eval --truth failed: $(cat "$WORK/stderr")"
grep -q '3 scenes, 2 instances, 1 scenes without any' "$WORK/stdout" ||
  bad "no scene count line: $(cat "$WORK/stdout")"
grep -q '^sift-magsac .* 2 (100%)' "$WORK/stdout" ||
  bad "sift-magsac does not find both instances: $(cat "$WORK/stdout")"
grep -q '^Homography truth' "$WORK/stdout" || bad "no homography table: $(cat "$WORK/stdout")"
python3 - "$WORK/out/truth-summary.json" <<'PY' || bad "truth-summary.json is not as expected"
import json, sys
d = json.load(open(sys.argv[1]))
assert d["scenes"] == 3, d
r = {x["method"]: x for x in d["results"]}
assert set(r) == {"keygraph", "sift-magsac"}, r
for x in r.values():
    assert x["instances"] == 2 and x["scenes_without_instances"] == 1, x
    assert x["homography_instances"] == 1, x
    assert x["median_ms"] > 0 and x["p90_ms"] >= x["median_ms"], x
s = r["sift-magsac"]
assert s["found"] == 2 and s["found_iou"] == 2 and s["homography_within_5px"] == 1, s
assert sum(b["instances"] for b in s["by_long_edge_px"]) == 2, s
# The ground truth asked of keygraph's verification: both poses (box from
# its corners in some order, graf from its homography) are confirmed by the
# frame's keypoints and have correct correspondences; the baselines are not
# measured.
k = r["keygraph"]
assert k["truth_measured"] == 2 and k["truth_verifiable"] == 2, k
assert k["truth_matched"] == 2 and k["truth_verifiable_matched"] == 2, k
assert k["median_truth_refound"] >= 12 and k["median_truth_shown"] > k["median_truth_refound"], k
assert s["truth_measured"] == 0 and s["truth_verifiable"] == 0, s
PY
python3 - "$WORK/out/truth-cases.csv" <<'PY' || bad "truth-cases.csv: truth support columns not as expected"
import csv, sys
rows = list(csv.DictReader(open(sys.argv[1])))
for r in rows:
    if r["instance"] == "-1" or r["method"] != "keygraph":
        assert r["truth_shown"] == "-1" and r["truth_refound"] == "-1", r
        assert r["truth_matches"] == "-1", r
    else:
        assert int(r["truth_refound"]) >= 12 and float(r["truth_z"]) >= 4, r
        assert r["truth_verifiable"] == "1" and int(r["truth_matches"]) >= 3, r
PY
grep -q '^At the ground-truth pose' "$WORK/stdout" || bad "no ground-truth support table: $(cat "$WORK/stdout")"
[ "$(wc -l <"$WORK/out/truth-cases.csv")" -eq 7 ] || bad "truth-cases.csv: expected 6 rows"
awk -F, 'NR==1 {n=NF} NF!=n {exit 1}' "$WORK/out/truth-cases.csv" ||
  bad "truth-cases.csv: rows and header disagree"
awk -F, 'NR==1 {n=NF} NF!=n {exit 1}' "$WORK/out/truth-detections.csv" ||
  bad "truth-detections.csv: rows and header disagree"
grep -q '^sift-magsac,0,2,frames/box_in_scene.png,box,true,0,' "$WORK/out/truth-detections.csv" ||
  bad "no true sift-magsac detection of box: $(cat "$WORK/out/truth-detections.csv")"
python3 -c "import sys; d=open(sys.argv[1],'rb').read(8); sys.exit(d != b'\x89PNG\r\n\x1a\n')" \
  "$WORK/out/truth-by-size.png" || bad "truth-by-size.png is not a PNG"
ls "$WORK/out" | grep -q '\.tmp' && bad "temporary files left in --out"

# The same with the index built by keygraph build: the keygraph counts agree
# (the errors may differ: the index searches graf3 for both models).
"$KG" build --name box "$DATA/box.png" --name graf "$DATA/graf1.png" -o "$WORK/both.kgi" \
  >/dev/null || bad "build both.kgi failed"
"$KG" eval --truth "$M" --index "$WORK/both.kgi" --methods keygraph >"$WORK/stdout2" 2>"$WORK/stderr" ||
  bad "eval --truth --index failed: $(cat "$WORK/stderr")"
counts() { grep -m1 '^keygraph ' "$1" | awk '{print $2, $3, $5}'; }
[ "$(counts "$WORK/stdout")" = "$(counts "$WORK/stdout2")" ] ||
  bad "--models and --index disagree: $(grep '^keygraph ' "$WORK/stdout" "$WORK/stdout2")"

finish
