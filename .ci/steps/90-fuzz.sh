#!/usr/bin/env bash
# Every libFuzzer target of the sanitize build (build/sanitize/tests/fuzz/
# fuzz_*), KG_CI_JOBS at a time, each on its seeds: those generated here
# (never committed) in $FUZZ/seeds/NAME and those in the repository in
# tests/fuzz/seeds/NAME (NAME: the target without fuzz_). The model index
# reader for 60 s; the evaluation's text readers, whose hand-written seeds
# are in the repository (manifests, models.json, corners.txt, homography
# files), 15 s each; the others (PGM reader, frame conversions, option
# parsers) 20 s each.
source .ci/lib.sh

BIN=build/sanitize/tests/fuzz
FUZZ=$KG_CI_TMP/fuzz
KG=build/ci/src/cli/keygraph
mkdir -p "$FUZZ/seeds/model_index"

# The index reader's seeds: real indexes from the CLI, small so that
# executions are fast: a 96x96 crop of box.png for each keygraph structure,
# MSER keypoints, SIFT vertex descriptors, and each descriptor encoding, a
# downsampled appearance; and the golden files of tests/data.
seeds=$FUZZ/seeds/model_index
crop=(--roi 100,60,96,96 "$OPENCV_DATA/box.png")
"$KG" build --structure 2 "${crop[@]}" -o "$seeds/structure2.kgi" >/dev/null
"$KG" build --structure 3 "${crop[@]}" -o "$seeds/structure3.kgi" >/dev/null
"$KG" build --structure 4 "${crop[@]}" -o "$seeds/structure4.kgi" >/dev/null
"$KG" build --detector mser "${crop[@]}" -o "$seeds/mser.kgi" >/dev/null
"$KG" build --vertex-descriptor sift "${crop[@]}" -o "$seeds/sift.kgi" >/dev/null
for encoding in float32 int16 int8; do
  "$KG" build --encoding "$encoding" "${crop[@]}" -o "$seeds/$encoding.kgi" >/dev/null
done
# An appearance downsampled (96 px to 48: scale 0.5), not the crop itself.
"$KG" build --set views.appearance_size=48 "${crop[@]}" -o "$seeds/appearance48.kgi" >/dev/null
# The golden files of every minor version (6.0, 6.1 without appearances;
# 6.2 and later with them).
cp tests/data/golden-*.kgi "$seeds/"
# The PGM reader's, frame conversions' and option parsers' seeds
# (tests/fuzz/make_seeds.py): small PGMs and a real JPEG whole and cut, frame
# layouts of every pixel format, command-line values with every --set
# parameter that `keygraph inspect` lists.
"$KG" inspect "$seeds/int8.kgi" >"$FUZZ/inspect.txt"
python3 tests/fuzz/make_seeds.py "$FUZZ/seeds" "$OPENCV_DATA" "$FUZZ/inspect.txt" | sed 's/^/  /'

# One line per target: SECONDS FUZZER SEED_DIR...
mapfile -t fuzzers < <(find "$BIN" -maxdepth 1 -type f -perm -u+x -name 'fuzz_*' | sort)
((${#fuzzers[@]})) || fail "no fuzz_* programs in $BIN (was the sanitize preset built?)"
jobs=()
for fuzzer in "${fuzzers[@]}"; do
  name=${fuzzer##*/fuzz_}
  seconds=20
  [[ -d tests/fuzz/seeds/$name ]] && seconds=15
  [[ $name == model_index ]] && seconds=60
  dirs=()
  for d in "$FUZZ/seeds/$name" "tests/fuzz/seeds/$name"; do [[ -d $d ]] && dirs+=("$d"); done
  ((${#dirs[@]})) || echo "WARNING: no seeds for fuzz_$name (add tests/fuzz/seeds/$name/)" >&2
  echo "fuzz_$name: ${seconds}s, seeds: ${dirs[*]:-none} ($(find "${dirs[@]}" -type f 2>/dev/null | wc -l) files)"
  jobs+=("$seconds $fuzzer ${dirs[*]}")
done
# Longest first, KG_CI_JOBS at a time (each fuzzer is one process).
printf '%s\n' "${jobs[@]}" | sort -rn |
  xargs -P "$KG_CI_JOBS" -L 1 sh -c 's=$1 f=$2; shift 2; bash .ci/fuzz-one.sh "$f" "$s" "$0" "$@"' "$FUZZ" ||
  fail "a fuzzer found a problem (its report above)"

# fuzz_model_index's mutator repairs checksums in 7 mutations of 8, so most
# inputs must get past them; most stopping at a checksum means the repair no
# longer matches the format (docs/FORMAT.md) and the fuzzer only tests the
# CRCs.
summary=$(grep -E '^fuzz_model_index: [0-9]+ inputs' "$FUZZ/log-fuzz_model_index" || true)
if [[ ! $summary =~ ^fuzz_model_index:\ ([0-9]+)\ inputs:\ [0-9]+\ rejected\ \(([0-9]+)\ at\ a\ checksum\),\ ([0-9]+)\ loaded ]]; then
  fail "no summary line from fuzz_model_index; see $FUZZ/log-fuzz_model_index"
fi
if ((BASH_REMATCH[2] * 2 > BASH_REMATCH[1] || BASH_REMATCH[3] == 0)); then
  fail "${BASH_REMATCH[2]} of ${BASH_REMATCH[1]} fuzz inputs stopped at a checksum" \
    "(${BASH_REMATCH[3]} loaded): the checksum repair in tests/fuzz/fuzz_model_index.cpp" \
    "no longer matches the format"
fi
