#!/bin/sh
# Reruns the Oxford, sign-benchmark and real-photo evaluations of
# docs/RESULTS.md, in one run (about 1.75 hours on 2 busy cores: the
# 400-crop run with every method took 36 min, the centre crops 6 min, the
# sign benchmark 10 min, the real photos 5 min, the angled block about 15
# min; more since the 45-degree defaults). The runs without options use
# the defaults of the binary: since 2026-12-04 the 45-degree views, so the
# sections before "Tilted views at 45 degrees by default" need $FRONTAL
# (below) added to reproduce their "defaults" rows.
#
#   docs/reproduce-results.sh [KEYGRAPH_BINARY] [OUT_DIR] [OXFORD_DIR] [REAL_DIR]
#
# defaults: build/release/src/cli/keygraph, build/results, $KG_DATA_DIR/oxford and
# $KG_DATA_DIR/real (KG_DATA_DIR defaults to ../shared/data).
# Writes OUT_DIR/<run>/ (summary JSON, CSV per case and per curve, PNG plots)
# and OUT_DIR/<run>.txt (the printed tables) for the runs:
#   oxford          10 seeded random crops per subset, every method, negatives, curves
#   oxford-centre   one centred crop per subset, every method, negatives
#   signs           the generated sign set (keygraph synth --seed 1, 300 frames)
#   synth           the sign benchmark (first 100 frames), indexes of 1, 10 and 50 signs,
#                   keygraph and the MAGSAC baselines; synth-ransac the RANSAC ones
#   ablation-*      one default changed at a time, centre crops
#   oxford-ENC      the 400 crops with float32 and int16 descriptors
#   real-*          the real photo sets (docs/EVAL.md): exit signs (all, dev, test),
#                   planar pairs, negatives; manifests in OUT_DIR/real-manifests
#   signs2, synth2-angled, synth2-tilt, oxford-angled, real-planar-pairs-angled
#                   the angled opt-in (circuit completion) on the held-out sign set
#                   (seed 2), the 400 crops and the photo pairs; synth2 and
#                   synth2-frontal the defaults and the frontal configuration there
# Copy OUT_DIR/oxford/*.png to docs/figures/ to refresh the committed plots.
set -eu
KG=${1:-build/release/src/cli/keygraph}
OUT=${2:-build/results}
OXFORD=${3:-${KG_DATA_DIR:-../shared/data}/oxford}
REAL=${4:-${KG_DATA_DIR:-../shared/data}/real}
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
# Real photos (RESULTS.md, "Real photos"): manifests referring to the images in place.
M="$OUT/real-manifests"
mkdir -p "$M"
"$KG" manifest exit-signs "$REAL/exit-signs" -o "$M/exit-signs.jsonl"
"$KG" manifest exit-signs "$REAL/exit-signs" -o "$M/exit-dev.jsonl" --split dev
"$KG" manifest exit-signs "$REAL/exit-signs" -o "$M/exit-test.jsonl" --split test
"$KG" manifest planar-pairs "$REAL/planar-pairs" -o "$M/planar-pairs.jsonl"
"$KG" manifest negatives "$REAL/negatives" -o "$M/negatives.jsonl"
for set in exit-signs exit-dev exit-test; do
  run "real-$set" eval --truth "$M/$set.jsonl" --models "$M/exit-sign-models.json" \
    --out "$OUT/real-$set" --gallery
done
run real-planar-pairs eval --truth "$M/planar-pairs.jsonl" --models "$M/planar-pair-models.json" \
  --out "$OUT/real-planar-pairs" --gallery
run real-negatives eval --truth "$M/negatives.jsonl" --models "$M/exit-sign-models.json" \
  --out "$OUT/real-negatives" --gallery
# The angled opt-in (RESULTS.md, "Circuit completion"): tilted views, the
# triangle check, circuit completion and 10 leaves, against tilted views
# and the check alone, on the held-out sign set, Oxford and the photo pairs.
TILT="--set views.max_tilt=60 --set views.tilt_levels=2 --set ransac.min_triangle_correlation=0.6 \
  --set graph.complete_circuits=0 --set graph.max_neighbour_rank=0 --set descriptor.max_search_leaves=20"
ANGLED="--set views.max_tilt=60 --set views.tilt_levels=2 --set ransac.min_triangle_correlation=0.6 \
  --set graph.complete_circuits=1 --set graph.max_neighbour_rank=0 --set descriptor.max_search_leaves=10"
# The frontal configuration, the defaults before 2026-12-04 (RESULTS.md,
# "Tilted views at 45 degrees by default").
FRONTAL="--set views.max_tilt=0 --set ransac.min_triangle_correlation=0 \
  --set graph.complete_circuits=0 --set graph.max_neighbour_rank=0 --set descriptor.max_search_leaves=20"
rm -rf "$OUT/signs2"
run signs2 synth -o "$OUT/signs2" --seed 2 --signs 50 --frames 300
# shellcheck disable=SC2086 # the option lists are meant to split
run synth2-angled eval --synth "$OUT/signs2" --sizes 1,10,50 --methods keygraph $ANGLED
run synth2 eval --synth "$OUT/signs2" --sizes 1,10,50 --methods keygraph
# shellcheck disable=SC2086
run synth2-frontal eval --synth "$OUT/signs2" --sizes 1,10,50 --methods keygraph $FRONTAL
# shellcheck disable=SC2086
run synth2-tilt eval --synth "$OUT/signs2" --sizes 1,10,50 --methods keygraph $TILT
# shellcheck disable=SC2086
run oxford-angled eval --dataset "$OXFORD" --crops 10 --seed 1 --methods keygraph --negatives \
  --out "$OUT/oxford-angled" $ANGLED
# shellcheck disable=SC2086
run real-planar-pairs-angled eval --truth "$M/planar-pairs.jsonl" \
  --models "$M/planar-pair-models.json" --methods keygraph $ANGLED
