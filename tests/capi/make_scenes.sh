#!/usr/bin/env bash
# The bindings' shared test data (fixture bindings_scenes): an index of two
# opencv-doc models, built by the keygraph tool, and the scenes they are
# found in as PGM frames.
#   make_scenes.sh KEYGRAPH KG_TO_PGM OPENCV_DATA_DIR OUT_DIR
# OUT_DIR/scenes.kgi holds "box" (box.png) and "graf" (the 300x300 crop of
# graf1.png at (200, 150): tests/support/opencv_scenes.h); OUT_DIR/
# box_in_scene.pgm and graf3.pgm are the frames (gray as OpenCV reads them).
set -euo pipefail
keygraph=$1 to_pgm=$2 data=$3 out=$4
mkdir -p "$out"
"$keygraph" build -q --no-look-alikes "$data/box.png" --name graf --roi 200,150,300,300 \
  "$data/graf1.png" -o "$out/scenes.kgi" >"$out/build.log"
"$to_pgm" "$data/box_in_scene.png" "$out/box_in_scene.pgm"
"$to_pgm" "$data/graf3.png" "$out/graf3.pgm"
echo "make_scenes: $out/scenes.kgi, box_in_scene.pgm, graf3.pgm"
