#!/bin/sh
# Reproduces every table and figure of the Oxford and sign-benchmark
# sections of docs/RESULTS.md, in one run (about 1.5 hours on 2 busy
# cores: the 400-crop run with every method took 36 min, the centre crops
# 6 min, the sign benchmark 10 min):
#
#   docs/reproduce-results.sh [KEYGRAPH_BINARY] [OUT_DIR] [OXFORD_DIR]
#
# defaults: build/release/src/cli/keygraph, build/results, $KG_DATA_DIR/oxford (../shared/data/oxford).
# Writes OUT_DIR/<run>/ (summary JSON, CSV per case and per curve, PNG plots)
# and OUT_DIR/<run>.txt (the printed tables) for the runs:
#   oxford          10 seeded random crops per subset, every method, negatives, curves
#   oxford-centre   one centred crop per subset, every method, negatives
#   signs           the generated sign set (keygraph synth --seed 1, 300 frames)
#   synth           the sign benchmark (first 100 frames), indexes of 1, 10 and 50 signs,
#                   keygraph and the MAGSAC baselines; synth-ransac the RANSAC ones
#   ablation-*      one default changed at a time, centre crops
#   oxford-ENC      the 400 crops with float32 and int16 descriptors
# Copy OUT_DIR/oxford/*.png to docs/figures/ to refresh the committed plots.
set -eu
KG=${1:-build/release/src/cli/keygraph}
OUT=${2:-build/results}
OXFORD=${3:-${KG_DATA_DIR:-../shared/data}/oxford}
[ -x "$KG" ] || { echo "no keygraph binary at $KG (cmake --preset release && cmake --build --preset release)" >&2; exit 1; }
mkdir -p "$OUT"
run() {  # run NAME ARGS...: tables to OUT/NAME.txt, timing to OUT/NAME.time
  name=$1
  shift
  echo "== $name: keygraph $*" >&2
  start=$(date +%s)
  "$KG" "$@" >"$OUT/$name.txt.tmp"
  mv "$OUT/$name.txt.tmp" "$OUT/$name.txt"
  echo "$(($(date +%s) - start)) s" >"$OUT/$name.time"
  cat "$OUT/$name.txt"
}
run oxford eval --dataset "$OXFORD" --crops 10 --seed 1 --methods all,keygraph-mser --negatives \
  --curves --out "$OUT/oxford"
run oxford-centre eval --dataset "$OXFORD" --centre --methods all --negatives --out "$OUT/oxford-centre"
rm -rf "$OUT/signs"
run signs synth -o "$OUT/signs" --seed 1 --signs 50 --frames 300
run synth eval --synth "$OUT/signs" --sizes 1,10,50 --frames 100 \
  --methods keygraph,sift-magsac,orb-magsac,akaze-magsac --out "$OUT/synth"
run synth-ransac eval --synth "$OUT/signs" --sizes 1,10,50 --frames 100 \
  --methods keygraph,sift-ransac,orb-ransac,akaze-ransac --out "$OUT/synth-ransac"
# Ablation and encodings (RESULTS.md, "Why the defaults differ" and "Model index size").
run ablation-defaults eval --dataset "$OXFORD" --centre --methods keygraph
for set in descriptor.similarity_threshold=0.5 graph.scene_sampling=random graph.max_anisotropy=0 \
  ransac.min_verification_z=0 descriptor.max_search_leaves=0 descriptor.encoding=float32 \
  descriptor.encoding=int16; do
  run "ablation-$set" eval --dataset "$OXFORD" --centre --methods keygraph --set "$set"
done
run ablation-paper eval --dataset "$OXFORD" --centre --methods keygraph \
  --set descriptor.similarity_threshold=0.5 --set graph.scene_sampling=random \
  --set graph.max_anisotropy=0 --set ransac.min_verification_z=0
for enc in float32 int16; do
  run "oxford-$enc" eval --dataset "$OXFORD" --crops 10 --seed 1 --methods keygraph \
    --set descriptor.encoding=$enc
done
