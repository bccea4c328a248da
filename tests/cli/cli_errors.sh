#!/bin/sh
# The keygraph CLI's contract on real files (DESIGN.md, "Quality bars"):
# every failure prints exactly one line on stderr, exits non-zero and leaves
# no output (not even a temporary file); the normal paths work and print
# what the docs say.
#
# usage: cli_errors.sh PATH/TO/keygraph OPENCV_DATA_DIR
set -u

KG=${1:?usage: cli_errors.sh KEYGRAPH_BINARY OPENCV_DATA_DIR}
DATA=${2:?usage: cli_errors.sh KEYGRAPH_BINARY OPENCV_DATA_DIR}

die() {
  echo "cli_errors: $*" >&2
  exit 1
}
[ -x "$KG" ] || die "no keygraph binary at $KG"
for f in box.png box_in_scene.png; do
  [ -f "$DATA/$f" ] || die "missing $DATA/$f (install Debian's opencv-doc package)"
done
command -v python3 >/dev/null 2>&1 || die "python3 is needed to validate JSON output"
# Absolute paths: failure cases run inside their own directories.
KG=$(cd "$(dirname "$KG")" && pwd)/$(basename "$KG")
DATA=$(cd "$DATA" && pwd)

WORK=$(mktemp -d "${TMPDIR:-/tmp}/kg_cli.XXXXXX") || die "mktemp failed"
trap 'rm -rf "$WORK"' EXIT
trap 'exit 1' HUP INT TERM
LOG=$WORK/log
mkdir "$LOG"

failures=0
checks=0
bad() {
  echo "FAIL: $*" >&2
  failures=$((failures + 1))
}

# Shared inputs.
IN=$WORK/in
mkdir "$IN"
echo "this is a text file, not an image" >"$IN/text.png"
: >"$IN/empty.png"
head -c 2000 "$DATA/box.png" >"$IN/truncated.png"

# expect_failure NAME CMD...: runs CMD inside a fresh directory $CASE (which
# the command line may name) and checks one stderr line, non-zero exit, no
# crash, and that nothing new appeared in $CASE.
CASE=
next_case() {
  checks=$((checks + 1))
  CASE=$WORK/case$checks
  mkdir "$CASE"
}
expect_failure() {
  name=$1
  shift
  before=$(ls -A "$CASE")
  (cd "$CASE" && "$@") >"$LOG/stdout" 2>"$LOG/stderr"
  rc=$?
  # wc -l counts newline characters: a message without one counts as 0.
  lines=$(wc -l <"$LOG/stderr" | tr -d ' ')
  after=$(ls -A "$CASE")
  if [ "$rc" -eq 0 ]; then
    bad "$name: exit status 0, expected a failure"
  elif [ "$rc" -ge 128 ]; then
    bad "$name: killed by signal $((rc - 128)) (crash)"
  fi
  if [ "$lines" -ne 1 ] || [ "$(wc -c <"$LOG/stderr" | tr -d ' ')" -le 1 ]; then
    bad "$name: expected one line on stderr, got $lines:"
    sed 's/^/    /' "$LOG/stderr" >&2
  elif ! grep -q '^keygraph: ' "$LOG/stderr"; then
    bad "$name: stderr line does not start with 'keygraph: ': $(cat "$LOG/stderr")"
  fi
  if [ "$before" != "$after" ]; then
    bad "$name: left files behind: $(echo "$after" | tr '\n' ' ')"
  fi
}

# --- build failures ---------------------------------------------------------
next_case
expect_failure "build: missing model file" "$KG" build "$CASE/missing.png" -o "$CASE/out.kgi"
next_case
cp "$IN/text.png" "$CASE/"
expect_failure "build: text file named .png" "$KG" build "$CASE/text.png" -o "$CASE/out.kgi"
next_case
cp "$IN/empty.png" "$CASE/"
expect_failure "build: empty image file" "$KG" build "$CASE/empty.png" -o "$CASE/out.kgi"
next_case
cp "$IN/truncated.png" "$CASE/"
expect_failure "build: truncated PNG" "$KG" build "$CASE/truncated.png" -o "$CASE/out.kgi"
next_case
expect_failure "build: no -o" "$KG" build "$DATA/box.png"
next_case
expect_failure "build: -o without a value" "$KG" build "$DATA/box.png" -o
next_case
expect_failure "build: no model images" "$KG" build -o "$CASE/out.kgi"
next_case
expect_failure "build: into a missing directory" \
  "$KG" build "$DATA/box.png" -o "$CASE/no_such_dir/out.kgi"
next_case
expect_failure "build: bad --structure" "$KG" build --structure 5 "$DATA/box.png" -o "$CASE/o.kgi"
next_case
expect_failure "build: --roi outside the image" \
  "$KG" build --roi 0,0,5000,10 "$DATA/box.png" -o "$CASE/out.kgi"
next_case
expect_failure "build: unknown option" "$KG" build --bogus "$DATA/box.png" -o "$CASE/out.kgi"
next_case
expect_failure "build: bad --encoding" "$KG" build --encoding int4 "$DATA/box.png" -o "$CASE/o.kgi"
next_case
expect_failure "build: --max-scale under 1" "$KG" build --max-scale 0.9 "$DATA/box.png" -o "$CASE/o.kgi"
grep -q "views.max_scale must be in \[1, 4\]" "$LOG/stderr" ||
  bad "build: --max-scale 0.9: the message does not give the range: $(cat "$LOG/stderr")"
# The appearance parameters (format 6.2) are range-checked, naming the field.
# So is the search budget (6.3), and the triangle patch check and
# progressive sampling (6.4), circuit completion (6.5), the neighbour
# rank of model arcs (6.6), the largest view scale (6.7; also against
# ransac.max_scale_change: 3 is above sqrt(8)) and the glowing twins (6.12).
for assignment in views.appearance_size=9999 views.appearance_size=-1 ransac.min_appearance=1.5 \
  ransac.min_appearance=nan descriptor.search_reference_models=-5 \
  ransac.min_triangle_correlation=1.5 ransac.progressive_sampling=2 graph.complete_circuits=2 \
  graph.max_neighbour_rank=-1 views.max_scale=0.5 views.max_scale=5 views.max_scale=3 \
  views.glow_max_size=-1; do
  next_case
  expect_failure "build: --set $assignment" \
    "$KG" build --set "$assignment" "$DATA/box.png" -o "$CASE/o.kgi"
  grep -q "${assignment%%=*}" "$LOG/stderr" ||
    bad "build: --set $assignment: the message does not name the parameter: $(cat "$LOG/stderr")"
done
next_case
expect_failure "build: --name after the last image" \
  "$KG" build "$DATA/box.png" --name late -o "$CASE/out.kgi"
next_case
expect_failure "build: two --name for one image" \
  "$KG" build --name a --name b "$DATA/box.png" -o "$CASE/out.kgi"

# --- a real index (also the positive build check) -----------------------------
INDEX=$WORK/box.kgi
checks=$((checks + 1))
if "$KG" build "$DATA/box.png" -o "$INDEX" >"$LOG/stdout" 2>"$LOG/stderr"; then
  grep -Eq '^box: [0-9]+ views, [0-9]+ keypoints, [0-9]+ arcs, [0-9]+ keygraphs, [0-9.]+ KB alone$' "$LOG/stdout" ||
    bad "build: no 'box: N views, N keypoints, N arcs, N keygraphs, N KB alone' line in: $(cat "$LOG/stdout")"
  # stderr (not a terminal here): one progress line per model, nothing else.
  grep -Eqx 'build: model 1/1 box \(100 %\), took [0-9]+:[0-9]{2}' "$LOG/stderr" &&
    [ "$(wc -l <"$LOG/stderr")" -eq 1 ] ||
    bad "build: expected one progress line on stderr, got: $(cat "$LOG/stderr")"
  [ -s "$INDEX" ] || bad "build: $INDEX missing or empty"
  for f in "$INDEX.tmp" "$WORK"/.box.kgi.*; do
    [ -e "$f" ] && bad "build: temporary $f left behind"
  done
else
  bad "build box.png failed: $(cat "$LOG/stderr")"
fi
[ -s "$INDEX" ] || die "no index to continue with ($failures failure(s) so far)"
# Progress: a line per model, with the model's name and the time left;
# none with --quiet. Models build on several threads, so the names come in
# the order the models finish: each once.
checks=$((checks + 1))
if "$KG" build --name first "$DATA/box.png" --name second "$DATA/box.png" -o "$WORK/two.kgi" \
  >"$LOG/stdout" 2>"$LOG/stderr"; then
  sed -n 1p "$LOG/stderr" | grep -Eqx 'build: model 1/2 (first|second) \(50 %\), [0-9]+:[0-9]{2} left' &&
    sed -n 2p "$LOG/stderr" | grep -Eqx 'build: model 2/2 (first|second) \(100 %\), took [0-9]+:[0-9]{2}' &&
    [ "$(grep -c ' first ' "$LOG/stderr")" -eq 1 ] && [ "$(grep -c ' second ' "$LOG/stderr")" -eq 1 ] &&
    [ "$(wc -l <"$LOG/stderr")" -eq 2 ] ||
    bad "build of two models: expected two progress lines, got: $(cat "$LOG/stderr")"
else
  bad "build of two models failed: $(cat "$LOG/stderr")"
fi
checks=$((checks + 1))
"$KG" build --quiet "$DATA/box.png" -o "$WORK/quiet.kgi" >"$LOG/stdout" 2>"$LOG/stderr" ||
  bad "build --quiet failed: $(cat "$LOG/stderr")"
[ -s "$LOG/stderr" ] && bad "build --quiet wrote to stderr: $(cat "$LOG/stderr")"
rm -f "$WORK/two.kgi" "$WORK/quiet.kgi"

# --name and --roi name the image that follows them; others keep their stem.
checks=$((checks + 1))
if "$KG" build "$DATA/box.png" --name crop --roi 10,10,200,200 "$DATA/box.png" \
  -o "$WORK/named.kgi" >"$LOG/stdout" 2>"$LOG/stderr"; then
  names=$(sed -n 's/^\([a-z]*\): [0-9]* views.*/\1/p' "$LOG/stdout" | tr '\n' ' ')
  [ "$names" = "box crop " ] || bad "build: model names '$names', expected 'box crop '"
else
  bad "build with --name before the second image failed: $(cat "$LOG/stderr")"
fi

# --- detect failures --------------------------------------------------------
SCENE=$DATA/box_in_scene.png
next_case
expect_failure "detect: missing index" "$KG" detect --index "$CASE/missing.kgi" "$SCENE"
next_case
cp "$IN/text.png" "$CASE/index.kgi"
expect_failure "detect: text file as index" "$KG" detect --index "$CASE/index.kgi" "$SCENE"
next_case
size=$(wc -c <"$INDEX" | tr -d ' ')
head -c $((size / 2)) "$INDEX" >"$CASE/half.kgi"
expect_failure "detect: truncated index (half)" "$KG" detect --index "$CASE/half.kgi" "$SCENE"
next_case
head -c $((size - 1)) "$INDEX" >"$CASE/short.kgi"
expect_failure "detect: truncated index (last byte)" "$KG" detect --index "$CASE/short.kgi" "$SCENE"
next_case
head -c 40 "$INDEX" >"$CASE/header.kgi"
expect_failure "detect: truncated index (inside header)" \
  "$KG" detect --index "$CASE/header.kgi" "$SCENE"
next_case
mkdir "$CASE/dir.kgi"
expect_failure "detect: directory as index" "$KG" detect --index "$CASE/dir.kgi" "$SCENE"
next_case
expect_failure "detect: missing scene" "$KG" detect --index "$INDEX" "$CASE/missing.png"
next_case
cp "$IN/truncated.png" "$CASE/"
expect_failure "detect: truncated scene" "$KG" detect --index "$INDEX" "$CASE/truncated.png"
next_case
expect_failure "detect: --draw into a missing directory" \
  "$KG" detect --index "$INDEX" --draw "$CASE/no_such_dir/out.png" "$SCENE"
next_case
expect_failure "detect: no --index" "$KG" detect "$SCENE"
next_case
expect_failure "detect: no scene" "$KG" detect --index "$INDEX"
next_case
expect_failure "detect: unknown option" "$KG" detect --index "$INDEX" --bogus "$SCENE"

# --- inspect -----------------------------------------------------------------
checks=$((checks + 1))
if "$KG" inspect "$INDEX" >"$LOG/stdout" 2>"$LOG/stderr"; then
  [ -s "$LOG/stderr" ] && bad "inspect: succeeded but wrote to stderr: $(cat "$LOG/stderr")"
  grep -Eq '^ +[0-9]+ +box +[0-9]+ +[0-9]+ ' "$LOG/stdout" ||
    bad "inspect: no model line for 'box' in: $(cat "$LOG/stdout")"
  # Every section, every checksum verified.
  [ "$(grep -Ec '^ +[0-9]+ .* crc ok$' "$LOG/stdout")" -eq 16 ] ||
    bad "inspect: expected 16 'crc ok' sections in: $(cat "$LOG/stdout")"
  # box.png (324x223) stored at the default 128 px: 128x88, 16 + 11264 bytes.
  grep -Eq '^appearance: 128 px long edge, 11\.0 KB$' "$LOG/stdout" ||
    bad "inspect: no appearance line in: $(cat "$LOG/stdout")"
  grep -Eq '^ +[0-9]+ +box +[0-9]+ .* 128x88$' "$LOG/stdout" ||
    bad "inspect: no 128x88 appearance in the model line for 'box'"
  grep -q 'crc BAD' "$LOG/stdout" && bad "inspect: a good index shows 'crc BAD'"
  grep -Eq '^format 6\.[0-9]+, ' "$LOG/stdout" || bad "inspect: no format line"
  grep -Eq '^  descriptor\.encoding +(float32|int16|int8)$' "$LOG/stdout" ||
    bad "inspect: parameter descriptor.encoding not shown"
  grep -Eq '^bytes per arc: [0-9.]+ ' "$LOG/stdout" || bad "inspect: no bytes-per-arc line"
  # One model: the budget as recorded (it grows beyond 10 models).
  grep -Eq '^search: 8 leaves per query \(descriptor\.max_search_leaves 8, grown beyond 10 models: this index has 1\)$' \
    "$LOG/stdout" || bad "inspect: no search budget line in: $(cat "$LOG/stdout")"
else
  bad "inspect of a good index failed: $(cat "$LOG/stderr")"
fi
# Each encoding builds, and inspect reports it.
for enc in float32 int16 int8; do
  checks=$((checks + 1))
  if "$KG" build --encoding $enc "$DATA/box.png" -o "$WORK/box-$enc.kgi" >"$LOG/stdout" 2>"$LOG/stderr" &&
    "$KG" inspect "$WORK/box-$enc.kgi" >"$LOG/stdout" 2>"$LOG/stderr"; then
    grep -Eq "^  descriptor\.encoding +$enc\$" "$LOG/stdout" ||
      bad "inspect: --encoding $enc index does not say $enc"
    grep -Eq "^ +5 +descriptors +$enc " "$LOG/stdout" ||
      bad "inspect: descriptors section of the $enc index not marked $enc"
  else
    bad "build/inspect --encoding $enc failed: $(cat "$LOG/stderr")"
  fi
done
# --max-tilt picks ASIFT's tilt levels unless views.tilt_levels is --set
# (before or after it); 0 turns the tilts off.
for tilt in "60:2" "45:1" "0:0" "60 --set views.tilt_levels=3:3" "--set views.tilt_levels=3 --max-tilt 60:3"; do
  checks=$((checks + 1))
  options=${tilt%:*}
  levels=${tilt##*:}
  case $options in --set*) ;; *) options="--max-tilt $options" ;; esac
  # shellcheck disable=SC2086 # the options are meant to be split
  if "$KG" build -q --no-look-alikes --min-size 150 $options "$DATA/box.png" -o "$WORK/box-tilt.kgi" \
    >"$LOG/stdout" 2>"$LOG/stderr" && "$KG" inspect "$WORK/box-tilt.kgi" >"$LOG/stdout" 2>"$LOG/stderr"; then
    grep -Eq "^  views\.tilt_levels +$levels\$" "$LOG/stdout" ||
      bad "build $options: views.tilt_levels is not $levels: $(grep tilt_levels "$LOG/stdout")"
  else
    bad "build/inspect $options failed: $(cat "$LOG/stderr")"
  fi
done
next_case
size=$(wc -c <"$INDEX" | tr -d ' ')
cp "$INDEX" "$CASE/corrupt.kgi"
# Change one byte in the middle of the file (inside a section's payload).
byte=$(od -An -tu1 -j $((size / 2)) -N1 "$INDEX" | tr -d ' ')
if [ "$byte" = 85 ]; then new='\252'; else new='\125'; fi
printf "$new" | dd of="$CASE/corrupt.kgi" bs=1 seek=$((size / 2)) conv=notrunc 2>/dev/null
cmp -s "$INDEX" "$CASE/corrupt.kgi" && bad "inspect: failed to corrupt the copy"
expect_failure "inspect: corrupt index" "$KG" inspect "$CASE/corrupt.kgi"
grep -q 'crc BAD' "$LOG/stdout" || bad "inspect: corrupt index shows no 'crc BAD' section"
grep -q 'checksum mismatch' "$LOG/stderr" || bad "inspect: corrupt index: $(cat "$LOG/stderr")"
next_case
head -c $((size / 2)) "$INDEX" >"$CASE/half.kgi"
expect_failure "inspect: truncated index" "$KG" inspect "$CASE/half.kgi"
next_case
cp "$IN/text.png" "$CASE/index.kgi"
expect_failure "inspect: text file as index" "$KG" inspect "$CASE/index.kgi"
next_case
expect_failure "inspect: missing index" "$KG" inspect "$CASE/missing.kgi"
next_case
expect_failure "inspect: no index" "$KG" inspect
next_case
expect_failure "inspect: two indexes" "$KG" inspect "$INDEX" "$INDEX"

# --- other commands ---------------------------------------------------------
next_case
expect_failure "unknown command" "$KG" frobnicate
next_case
expect_failure "demo: unknown option" "$KG" demo --bogus
next_case
expect_failure "demo: missing output directory" "$KG" demo --out "$CASE/no_such_dir"

# --- detect: JSON ------------------------------------------------------------
checks=$((checks + 1))
if "$KG" detect --index "$INDEX" --json "$SCENE" >"$LOG/json" 2>"$LOG/stderr"; then
  lines=$(wc -l <"$LOG/json" | tr -d ' ')
  [ "$lines" -eq 1 ] || bad "detect --json: $lines lines on stdout, expected 1"
  [ -s "$LOG/stderr" ] && bad "detect --json: wrote to stderr: $(cat "$LOG/stderr")"
  python3 -c 'import json,sys; json.loads(sys.stdin.read())' <"$LOG/json" ||
    bad "detect --json: output is not valid JSON: $(head -c 300 "$LOG/json")"
  python3 - "$LOG/json" <<'EOF' || bad "detect --json: unexpected content: $(head -c 600 "$LOG/json")"
import json, numbers, sys
doc = json.loads(open(sys.argv[1]).read())
found = doc["detections"]
assert len(found) == 1, "want one detection, got %d" % len(found)
d = found[0]
assert d["model"] == "box", d["model"]
h = d["homography"]
assert len(h) == 9 and all(isinstance(v, numbers.Real) and not isinstance(v, bool) for v in h), h
# box.png in box_in_scene.png: about 50 inliers, a confident detection.
assert isinstance(d["confidence"], numbers.Real) and 0.9 < d["confidence"] <= 1.0, d["confidence"]
# The frame's stage counts, and no per-frame limit reached on a small index.
st = doc["stats"]
assert st["arc_matches"] > 0 and st["correspondences"] > 0, st
assert 0 <= st["patch_rejections"] <= st["correspondences"], st
# The defaults complete circuits: a funnel that narrows down to the
# correspondences selected.
c = st["completion"]
assert c["tried"] >= c["clockwise"] >= c["plausible"] >= c["closed"] >= st["correspondences"], st
assert st["truncated"] == [], st
EOF
else
  bad "detect --json failed (exit $?): $(cat "$LOG/stderr")"
fi

# --- detect: --draw ------------------------------------------------------------
checks=$((checks + 1))
DRAWN=$WORK/drawn.png
if "$KG" detect --index "$INDEX" --draw "$DRAWN" "$SCENE" >"$LOG/stdout" 2>"$LOG/stderr"; then
  [ "$(head -c 4 "$DRAWN" 2>/dev/null | tail -c 3)" = PNG ] || bad "detect --draw: $DRAWN is not a PNG"
  for f in "$WORK"/.tmp-* "$WORK"/.drawn.png.*; do
    [ -e "$f" ] && bad "detect --draw: temporary image $f left behind"
  done
else
  bad "detect --draw failed: $(cat "$LOG/stderr")"
fi

# --- demo ----------------------------------------------------------------------
checks=$((checks + 1))
DEMO=$WORK/demo
mkdir "$DEMO"
if "$KG" demo --out "$DEMO" --data "$DATA" >"$LOG/stdout" 2>"$LOG/stderr"; then
  [ "$(head -c 4 "$DEMO/demo.png" 2>/dev/null | tail -c 3)" = PNG ] ||
    bad "demo: $DEMO/demo.png missing or not a PNG"
else
  bad "demo --out failed: $(cat "$LOG/stderr")"
fi

if [ "$failures" -ne 0 ]; then
  echo "cli_errors: $failures failure(s) in $checks checks" >&2
  exit 1
fi
echo "cli_errors: all $checks checks passed"
