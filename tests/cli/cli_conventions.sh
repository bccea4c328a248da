#!/bin/bash
# What a new user meets on the command line (issue 39), on real images:
#   --version           the library version and the index formats read
#   directories         build and detect take a folder; build a models.json
#   -o                  -o, --out and --output on every command that writes
#   --draw DIR          one picture per scene, in colour for a colour scene
#   repeated options    a value option twice is a usage error; --set repeats
#   --                  ends the options (a scene named -scene.png)
#   -q                  on every command that shows progress or status
#   --max-side          a model photo over the pixel limit, downsampled
#   outputs first       a --draw that cannot be written fails before any scene
#   JSON lines          valid for a name that is not UTF-8; one line per scene,
#                       an error field for a scene that cannot be read
#   messages            the command named, full parameter names, 1 model,
#                       no "nan" for empty bins, live on an MSER index
#   labels              an upside-down detection, drawn with its name
#
# usage: cli_conventions.sh KEYGRAPH OPENCV_DATA_DIR KG_IMAGE_TOOL VERSION
set -u

KG=${1:?usage: cli_conventions.sh KEYGRAPH OPENCV_DATA_DIR KG_IMAGE_TOOL VERSION}
DATA=${2:?}
TOOL=${3:?}
VERSION=${4:?}
KG=$(cd "$(dirname "$KG")" && pwd)/$(basename "$KG")
DATA=$(cd "$DATA" && pwd)

TEST_NAME=cli_conventions
. "$(dirname "$0")/test_support.sh"
lines() { wc -l <"$1" | tr -d ' '; }
# Quick builds for the checks that do not need the default views.
QUICK=(-q --no-look-alikes --max-tilt 0 --min-size 0)

SCENE=$DATA/box_in_scene.png
INDEX=$WORK/box.kgi
"$KG" build -q --no-look-alikes "$DATA/box.png" -o "$INDEX" >/dev/null 2>"$ERR" || {
  echo "cli_conventions: cannot build box.kgi: $(cat "$ERR")" >&2
  exit 1
}

# --- --version --------------------------------------------------------------------
run "$KG" --version
format=$("$KG" inspect "$INDEX" | sed -n 's/^format \([0-9]*\.[0-9]*\),.*/\1/p')
major=${format%.*}
if [ "$rc" -ne 0 ] || [ -s "$ERR" ] ||
  ! sed -n 1p "$OUT" | grep -Eqx "keygraph $VERSION \(desktop build, OpenCV [0-9.]+\)" ||
  ! sed -n 2p "$OUT" | grep -qF "index format: writes $format; reads $major.0 to $format"; then
  bad "--version: exit $rc (index format $format): $(cat "$OUT" "$ERR")"
fi
run "$KG" --help
grep -q -- "--version" "$OUT" || bad "keygraph --help does not mention --version"

# --- directories and models.json --------------------------------------------------
MODELS=$WORK/models
mkdir "$MODELS"
cp "$DATA/box.png" "$MODELS/box.png"
cp "$DATA/box.png" "$MODELS/crate.png"
echo "not an image" >"$MODELS/notes.txt"
run "$KG" build "${QUICK[@]}" "$MODELS" -o "$WORK/dir.kgi"
names=$(sed -n 's/^\([a-z]*\): [0-9]* views.*/\1/p' "$OUT" | tr '\n' ' ')
[ "$rc" -eq 0 ] && [ "$names" = "box crate " ] ||
  bad "build DIR: exit $rc, models '$names', expected 'box crate ': $(cat "$ERR")"
# models.json: names, files relative to it, an ROI; beside an image argument.
cat >"$MODELS/models.json" <<'EOF'
{"whole": "box.png", "label": {"file": "crate.png", "roi": [20, 20, 200, 150]}}
EOF
run "$KG" build "${QUICK[@]}" "$MODELS/models.json" --name extra "$DATA/box.png" -o "$WORK/json.kgi"
names=$(sed -n 's/^\([a-z]*\): [0-9]* views.*/\1/p' "$OUT" | sort | tr '\n' ' ')
[ "$rc" -eq 0 ] && [ "$names" = "extra label whole " ] ||
  bad "build models.json: exit $rc, models '$names': $(cat "$ERR")"
"$KG" inspect "$WORK/json.kgi" | grep -Eq '^ +[0-9]+ +label +.* 128x96$' ||
  bad "build models.json: the ROI (200x150) was not applied to 'label'"
# A directory with a models.json reads it.
run "$KG" build "${QUICK[@]}" "$MODELS" -o "$WORK/dir.kgi"
names=$(sed -n 's/^\([a-z]*\): [0-9]* views.*/\1/p' "$OUT" | sort | tr '\n' ' ')
[ "$rc" -eq 0 ] && [ "$names" = "label whole " ] || bad "build DIR with models.json: '$names'"
run "$KG" build --name x "$MODELS" -o "$WORK/x.kgi"
one_error 2 "--name and --roi apply to one model image" || bad "build --name DIR: exit $rc: $(cat "$ERR")"
# detect on a directory: its images in name order.
SCENES=$WORK/scenes
mkdir "$SCENES"
cp "$SCENE" "$SCENES/b.png"
cp "$DATA/box.png" "$SCENES/a.png"
run "$KG" detect --index "$INDEX" --json "$SCENES"
if [ "$rc" -ne 0 ] || [ "$(lines "$OUT")" -ne 2 ]; then
  bad "detect DIR: exit $rc, $(lines "$OUT") lines: $(cat "$ERR")"
else
  python3 - "$OUT" "$SCENES" <<'EOF' || bad "detect DIR: $(cat "$OUT")"
import json, sys
docs = [json.loads(l) for l in open(sys.argv[1])]
assert [d["scene"] for d in docs] == [sys.argv[2] + "/a.png", sys.argv[2] + "/b.png"], docs
assert all(d["detections"][0]["model"] == "box" for d in docs), docs
EOF
fi

# --- -o, --out, --output -------------------------------------------------------------
for spelling in -o --out --output; do
  run "$KG" build "${QUICK[@]}" "$DATA/box.png" "$spelling" "$WORK/o$spelling.kgi"
  [ "$rc" -eq 0 ] && [ -s "$WORK/o$spelling.kgi" ] || bad "build $spelling: exit $rc: $(cat "$ERR")"
  mkdir -p "$WORK/demo$spelling"
  run "$KG" demo "$spelling" "$WORK/demo$spelling" --data "$DATA"
  [ "$rc" -eq 0 ] && [ -s "$WORK/demo$spelling/demo.png" ] || bad "demo $spelling: exit $rc: $(cat "$ERR")"
done
for c in build demo eval manifest synth; do
  "$KG" "$c" --help | grep -q '^  -o, --out, --output ' || bad "$c --help has no '-o, --out, --output'"
done
# The demo without -o leaves nothing where it runs.
mkdir "$WORK/checkout"
run sh -c "cd '$WORK/checkout' && TMPDIR='$WORK' '$KG' demo --data '$DATA'"
[ "$rc" -eq 0 ] && [ -z "$(ls -A "$WORK/checkout")" ] && grep -q "wrote $WORK/keygraph-demo-[0-9]*/demo.png" "$OUT" ||
  bad "demo without -o: exit $rc, left '$(ls -A "$WORK/checkout")': $(cat "$OUT" "$ERR")"

# --- --draw DIR: one picture per scene, in colour for a colour scene ------------------
DRAWN=$WORK/drawn
mkdir "$DRAWN"
run "$KG" detect --index "$INDEX" --draw "$DRAWN" "$SCENE" "$DATA/fruits.jpg"
if [ "$rc" -ne 0 ] || [ "$(ls "$DRAWN" | tr '\n' ' ')" != "box_in_scene.png fruits.png " ]; then
  bad "detect --draw DIR: exit $rc, pictures: $(ls "$DRAWN"): $(cat "$ERR")"
else
  colour=$("$TOOL" colour "$DRAWN/fruits.png")
  scene_colour=$("$TOOL" colour "$DRAWN/box_in_scene.png")
  # fruits.jpg is a colour photo: its picture too. box_in_scene is gray:
  # only the outline and the name are in colour.
  awk -v c="$colour" 'BEGIN { exit !(c > 20) }' || bad "detect --draw: fruits.png is not in colour ($colour %)"
  awk -v c="$scene_colour" 'BEGIN { exit !(c > 0.1 && c < 10) }' ||
    bad "detect --draw: box_in_scene.png: $scene_colour % coloured pixels, expected an outline and a name"
fi

# --- repeated options, -- ----------------------------------------------------------------
run "$KG" detect --index "$INDEX" --index "$INDEX" "$SCENE"
one_error 2 "keygraph: detect: --index given twice" || bad "--index twice: exit $rc: $(cat "$ERR")"
run "$KG" build "$DATA/box.png" -o "$WORK/a.kgi" --output "$WORK/b.kgi"
one_error 2 "--output given twice" || bad "build -o twice: exit $rc: $(cat "$ERR")"
[ -e "$WORK/a.kgi" ] || [ -e "$WORK/b.kgi" ] && bad "build -o twice wrote an index"
run "$KG" build "${QUICK[@]}" --set ransac.min_inliers=8 --set ransac.max_instances=2 "$DATA/box.png" \
  -o "$WORK/set.kgi"
[ "$rc" -eq 0 ] && "$KG" inspect "$WORK/set.kgi" | grep -Eq '^  ransac\.min_inliers +8$' &&
  "$KG" inspect "$WORK/set.kgi" | grep -Eq '^  ransac\.max_instances +2$' ||
  bad "build with two --set: exit $rc: $(cat "$ERR")"
cp "$SCENE" "$WORK/-scene.png"
run sh -c "cd '$WORK' && '$KG' detect --index box.kgi -- -scene.png"
[ "$rc" -eq 0 ] && grep -q '^-scene.png: 1 detection(s)' "$OUT" || bad "detect -- -scene.png: exit $rc: $(cat "$OUT" "$ERR")"
run sh -c "cd '$WORK' && '$KG' detect --index box.kgi -scene.png"
one_error 2 "unknown option -scene.png" || bad "detect -scene.png without --: exit $rc: $(cat "$ERR")"

# --- -q on every command that shows progress or status -----------------------------------
for c in build eval synth repeatability live; do
  "$KG" "$c" --help | grep -q '^  -q, --quiet ' || bad "$c --help has no -q, --quiet"
done
FRAMES=$WORK/frames
mkdir "$FRAMES"
cp "$SCENE" "$FRAMES/"
run "$KG" live --index "$INDEX" --images "$FRAMES" -q
[ "$rc" -eq 0 ] && [ ! -s "$ERR" ] && grep -q 'box_in_scene.png: 1 detection(s)' "$OUT" ||
  bad "live -q: exit $rc, stderr: $(cat "$ERR")"
run "$KG" live --index "$INDEX" --images "$FRAMES"
grep -q '^live: 1 frame in ' "$ERR" || bad "live summary: $(cat "$ERR")"

# --- --max-side: a photo over the 16.7 MP limit -------------------------------------------
# box.png x 16: 5184 x 3568 = 18.5 MP, a JPEG.
"$TOOL" scale "$DATA/box.png" "$WORK/big.jpg" 16 || bad "kg_image_tool scale failed"
run "$KG" build -q "$WORK/big.jpg" -o "$WORK/big.kgi"
one_error 1 "pixels (the limit), not decoded; --max-side PX" || bad "build of a 18.5 MP JPEG: exit $rc: $(cat "$ERR")"
[ -e "$WORK/big.kgi" ] && bad "build of a 18.5 MP JPEG wrote an index"
run "$KG" build -q --no-look-alikes --max-side 324 "$WORK/big.jpg" -o "$WORK/big.kgi"
[ "$rc" -eq 0 ] || bad "build --max-side 324: exit $rc: $(cat "$ERR")"
"$KG" inspect "$WORK/big.kgi" | grep -Eq '^ +0 +big +.* 128x88$' ||
  bad "build --max-side 324: the model is not box.png's size (128x88 appearance)"
run "$KG" detect --index "$WORK/big.kgi" --json "$SCENE"
python3 -c 'import json,sys; d=json.loads(open(sys.argv[1]).read()); assert [x["model"] for x in d["detections"]] == ["big"], d' \
  "$OUT" || bad "the --max-side model is not found in box_in_scene: $(cat "$OUT" "$ERR")"
"$TOOL" scale "$DATA/box.png" "$WORK/big.png" 16 || bad "kg_image_tool scale failed"
run "$KG" build -q --max-side 324 "$WORK/big.png" -o "$WORK/bigpng.kgi"
one_error 1 "--max-side downsamples JPEG files only" || bad "build --max-side of a big PNG: exit $rc: $(cat "$ERR")"

# --- outputs checked before the first scene -----------------------------------------------
PHOTOS=$WORK/photos
mkdir "$PHOTOS"
cp "$SCENE" "$PHOTOS/p1.png"
cp "$SCENE" "$PHOTOS/p2.png"
# A missing directory, no extension, the scene itself (as a file name, and
# through its own directory): one error line, no scene detected.
for draw in "$WORK/missing/x.png" "$WORK/noext" "$WORK/missing/" "$PHOTOS/p1.png" "$PHOTOS/"; do
  run "$KG" detect --index "$INDEX" --draw "$draw" "$PHOTOS/p1.png"
  one_error 1 "keygraph: detect: --draw" && [ ! -s "$OUT" ] ||
    bad "detect --draw $draw: exit $rc, stdout $(lines "$OUT") lines: $(cat "$ERR")"
done
for draw in "$WORK/missing/x.png" "$WORK/noext" "$WORK/missing/" "$PHOTOS/"; do
  run "$KG" detect --index "$INDEX" --draw "$draw" "$PHOTOS/p1.png" "$PHOTOS/p2.png"
  one_error 1 "keygraph: detect: --draw" && [ ! -s "$OUT" ] ||
    bad "detect --draw $draw (two scenes): exit $rc, stdout $(lines "$OUT") lines: $(cat "$ERR")"
done
cmp -s "$SCENE" "$PHOTOS/p1.png" || bad "detect --draw p1.png changed the input p1.png"
[ "$(ls "$PHOTOS" | tr '\n' ' ')" = "p1.png p2.png " ] || bad "detect --draw left files: $(ls -A "$PHOTOS")"

# --- JSON lines -------------------------------------------------------------------------
latin1=$WORK/$(printf 'sc\351ne.png')
cp "$SCENE" "$latin1"
echo "text" >"$WORK/text.png"
run "$KG" detect --index "$INDEX" --json "$latin1" "$WORK/nothere.png" "$WORK/text.png" "$SCENE"
if [ "$rc" -ne 1 ] || [ "$(lines "$OUT")" -ne 4 ] || [ "$(lines "$ERR")" -ne 2 ]; then
  bad "detect --json with unreadable scenes: exit $rc, $(lines "$OUT") JSON lines, stderr: $(cat "$ERR")"
else
  python3 - "$OUT" <<'EOF' || bad "detect --json: $(cat "$OUT")"
import json, sys
docs = [json.loads(l) for l in open(sys.argv[1], encoding="utf-8")]
assert docs[0]["scene"].endswith("sc\ufffdne.png") and docs[0]["detections"], docs[0]
assert docs[1]["scene"].endswith("nothere.png") and "no such file" in docs[1]["error"], docs[1]
assert docs[2]["scene"].endswith("text.png") and "not a readable image" in docs[2]["error"], docs[2]
assert "error" not in docs[3] and docs[3]["detections"], docs[3]
EOF
fi

# --- messages ---------------------------------------------------------------------------
run "$KG" detect --index "$INDEX" nothere.jpg
one_error 1 "keygraph: detect: nothere.jpg: no such file" || bad "detect nothere.jpg: $(cat "$ERR")"
run "$KG" build --set ransac.min_inliers=2 "$DATA/box.png" -o "$WORK/m.kgi"
grep -q "ransac.min_inliers" "$ERR" && [ "$rc" -ne 0 ] || bad "--set ransac.min_inliers=2: $(cat "$ERR")"
run "$KG" build "${QUICK[@]}" "$DATA/box.png" -o "$WORK/one.kgi"
grep -qx "wrote $WORK/one.kgi (1 model)" "$OUT" || bad "build of one model: $(tail -n 1 "$OUT")"
run "$KG" inspect "$WORK/one.kgi"
grep -q '^total: 1 model, ' "$OUT" || bad "inspect of one model: $(grep '^total' "$OUT")"
run "$KG" bench --index "$WORK/one.kgi" --repeat 1 "$SCENE"
grep -Eq ': 1 model, .*; 1 frame( file)?, 1 run each, 1 thread$' "$OUT" || bad "bench of one model: $(head -n 1 "$OUT")"
run "$KG" build "${QUICK[@]}" --detector mser "$DATA/box.png" -o "$WORK/mser.kgi"
run "$KG" live --index "$WORK/mser.kgi" --images "$FRAMES"
if ! one_error 1 "keygraph: live: " || grep -q "needs OpenCV" "$ERR" || ! grep -q "core detector" "$ERR"; then
  bad "live on an MSER index: exit $rc: $(cat "$ERR")"
fi
run "$KG" bench --index "$WORK/mser.kgi" "$SCENE"
grep -q "needs OpenCV" "$ERR" && bad "bench on an MSER index says it needs OpenCV: $(cat "$ERR")"
# Empty size bins of a small synthetic benchmark: dashes, never nan or 0/0.
run "$KG" synth -q -o "$WORK/synth" --signs 2 --frames 4 --seed 3
run "$KG" eval -q --synth "$WORK/synth"
if [ "$rc" -ne 0 ]; then
  bad "eval --synth: exit $rc: $(cat "$ERR")"
elif grep -Eqi 'nan|0/0' "$OUT"; then
  bad "eval --synth prints nan or 0/0: $(grep -Ei 'nan|0/0' "$OUT")"
fi

# --- labels: an upside-down detection ------------------------------------------------------
"$TOOL" scale "$SCENE" "$WORK/turned.png" 1 --turn || bad "kg_image_tool scale --turn failed"
run "$KG" detect --index "$INDEX" --json --draw "$WORK/turned-drawn.png" "$WORK/turned.png"
[ "$rc" -eq 0 ] && [ -s "$WORK/turned-drawn.png" ] &&
  python3 -c 'import json,sys; d=json.loads(open(sys.argv[1]).read()); assert d["detections"][0]["model"] == "box"' "$OUT" ||
  bad "detect on the turned scene: exit $rc: $(cat "$OUT" "$ERR")"

finish
