#!/bin/sh
# keygraph build's model quality report end to end: build prints it and
# stores it in the index, inspect prints it back from the file (with every
# view), a plain rectangle gets its warning, --draw-model writes one valid
# PNG per model of the model's size, and a bad --draw-model fails cleanly.
#
# usage: cli_quality.sh PATH/TO/keygraph OPENCV_DATA_DIR [sanitized]
#   sanitized (a sanitizer build, where building the 4 models of the -j
#   check takes 37 s of CPU, twice): those two builds scale the models to
#   256 px on their long edge (--max-side 256, a 5th of the work); the same
#   checks on smaller models
set -u
KG=${1:?usage: cli_quality.sh KEYGRAPH_BINARY OPENCV_DATA_DIR [sanitized]}
DATA=${2:?usage: cli_quality.sh KEYGRAPH_BINARY OPENCV_DATA_DIR [sanitized]}
JOBS_SIZE=
[ "${3:-}" = sanitized ] && JOBS_SIZE="--max-side 256"
command -v python3 >/dev/null 2>&1 || { echo "python3 is needed to make and read PNGs" >&2; exit 1; }
TEST_NAME=cli_quality
. "$(dirname "$0")/test_support.sh"

# A plain rectangle as a binary PGM (no image library needed): a dark
# frame 6 px wide on white, 240 x 160.
python3 - "$WORK/rectangle.pgm" <<'EOF'
import sys
w, h = 240, 160
rows = []
for y in range(h):
    row = bytearray(b"\xff" * w)
    for x in range(w):
        inside = 20 <= x < 220 and 20 <= y < 140
        core = 26 <= x < 214 and 26 <= y < 134
        if inside and not core:
            row[x] = 30
    rows.append(bytes(row))
with open(sys.argv[1], "wb") as f:
    f.write(b"P5\n%d %d\n255\n" % (w, h) + b"".join(rows))
EOF

"$KG" build "$DATA/box.png" --name "flat/rect" "$WORK/rectangle.pgm" --draw-model "$WORK/pictures" \
  -o "$WORK/q.kgi" >"$WORK/build.txt" 2>"$WORK/build.err" || bad "build failed: $(cat "$WORK/build.err")"
grep -q '^index rating: ' "$WORK/build.txt" || bad "build printed no index rating"
grep -q '^warning: flat/rect: too few keypoints or keygraphs to be found at any size' "$WORK/build.txt" ||
  bad "no warning for the plain rectangle: $(grep warning "$WORK/build.txt")"
grep -q '^warning: box:' "$WORK/build.txt" && bad "box.png warned about: $(grep 'warning: box' "$WORK/build.txt")"

"$KG" inspect "$WORK/q.kgi" >"$WORK/inspect.txt" 2>&1 || bad "inspect failed: $(cat "$WORK/inspect.txt")"
# The report read back from the file is the one build printed.
sed -n '/^quality/,/^index rating/p' "$WORK/build.txt" >"$WORK/from_build.txt"
sed -n '/^quality/,/^index rating/p' "$WORK/inspect.txt" | grep -v '^         view ' >"$WORK/from_file.txt"
cmp -s "$WORK/from_build.txt" "$WORK/from_file.txt" ||
  bad "inspect's report differs from build's: $(diff "$WORK/from_build.txt" "$WORK/from_file.txt")"
views=$(grep -c '^         view .* keypoints, .* arcs, .* keygraphs$' "$WORK/inspect.txt")
[ "$views" -ge 2 ] || bad "inspect printed $views view lines"

# One PNG per model (the '/' of a name made safe), each the model's size.
python3 - "$WORK/pictures" <<'EOF' || bad "--draw-model pictures"
import os, struct, sys
d = sys.argv[1]
want = {"box.png": (324, 223), "flat_rect.png": (240, 160)}
names = sorted(os.listdir(d))
assert names == sorted(want), names
for name, size in want.items():
    data = open(os.path.join(d, name), "rb").read()
    assert data[:8] == b"\x89PNG\r\n\x1a\n", name + ": not a PNG"
    assert data[12:16] == b"IHDR", name + ": no IHDR"
    w, h, depth, colour = struct.unpack(">IIBB", data[16:26])
    assert (w, h) == size, (name, w, h)
    assert depth == 8 and colour == 2, (name, depth, colour)  # 8-bit RGB
    assert data[-8:-4] == b"IEND", name + ": truncated"
EOF

# --draw-model into a file: one line on stderr, no index left behind.
: >"$WORK/a_file"
"$KG" build "$DATA/box.png" --draw-model "$WORK/a_file" -o "$WORK/none.kgi" \
  >/dev/null 2>"$WORK/err.txt" && bad "--draw-model into a file succeeded"
[ "$(wc -l <"$WORK/err.txt")" -eq 1 ] || bad "--draw-model into a file: $(cat "$WORK/err.txt")"
[ -e "$WORK/none.kgi" ] && bad "--draw-model into a file left an index behind"

# --no-look-alikes: the report says the check was not run.
"$KG" build --no-look-alikes "$DATA/box.png" -o "$WORK/n.kgi" >"$WORK/n.txt" 2>&1 ||
  bad "--no-look-alikes failed: $(cat "$WORK/n.txt")"
grep -q 'look-alike check not run' "$WORK/n.txt" || bad "--no-look-alikes not reported"

# Models built on several threads (-j) give the same index, byte for byte,
# quality report and all, and the same lines on stdout.
set -- "$DATA/box.png" "$DATA/box_in_scene.png" "$DATA/graf1.png" "$DATA/graf3.png"
# shellcheck disable=SC2086
"$KG" build $JOBS_SIZE -j 1 "$@" -o "$WORK/j1.kgi" >"$WORK/j1.txt" 2>&1 || bad "build -j 1 failed: $(cat "$WORK/j1.txt")"
# shellcheck disable=SC2086
"$KG" build $JOBS_SIZE -j 3 "$@" -o "$WORK/j3.kgi" >"$WORK/j3.txt" 2>&1 || bad "build -j 3 failed: $(cat "$WORK/j3.txt")"
cmp -s "$WORK/j1.kgi" "$WORK/j3.kgi" || bad "build -j 3 wrote another index than -j 1"
grep -v -e '^build: ' -e '^wrote ' "$WORK/j1.txt" >"$WORK/j1.out"
grep -v -e '^build: ' -e '^wrote ' "$WORK/j3.txt" >"$WORK/j3.out"
cmp -s "$WORK/j1.out" "$WORK/j3.out" || bad "build -j 3 printed: $(diff "$WORK/j1.out" "$WORK/j3.out")"
# A model image that cannot be read fails the build before any model is
# built, on one line, with no index left behind, whatever -j.
: >"$WORK/empty.png"
"$KG" build -j 2 "$DATA/box.png" "$WORK/empty.png" "$DATA/graf1.png" -o "$WORK/bad.kgi" \
  >"$WORK/bad.txt" 2>"$WORK/bad.err" && bad "build -j 2 with an empty image succeeded"
[ "$(wc -l <"$WORK/bad.err")" -eq 1 ] || bad "build -j 2, empty image: $(cat "$WORK/bad.err")"
grep -q 'empty.png' "$WORK/bad.err" || bad "build -j 2, empty image: not named: $(cat "$WORK/bad.err")"
[ -e "$WORK/bad.kgi" ] && bad "build -j 2 with an empty image left an index behind"

finish
