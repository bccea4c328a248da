#!/bin/sh
# keygraph synth and keygraph eval on bad input: one line on stderr, a
# non-zero exit, nothing left behind; and a small synth set end to end
# (written, evaluated, its JSON summary valid).
#
# usage: cli_eval_synth.sh PATH/TO/keygraph
set -u
KG=${1:?usage: cli_eval_synth.sh KEYGRAPH_BINARY}
[ -x "$KG" ] || { echo "no keygraph binary at $KG" >&2; exit 1; }
KG=$(cd "$(dirname "$KG")" && pwd)/$(basename "$KG")  # commands run in other directories
command -v python3 >/dev/null 2>&1 || { echo "python3 is needed to validate JSON" >&2; exit 1; }
TEST_NAME=cli_eval_synth
. "$(dirname "$0")/test_support.sh"

# expect_failure NAME CMD...: one stderr line, non-zero exit, no new files in $WORK/case.
expect_failure() {
  name=$1
  shift
  rm -rf "$WORK/case" && mkdir "$WORK/case"
  (cd "$WORK/case" && "$@") >"$WORK/stdout" 2>"$WORK/stderr"
  rc=$?
  [ $rc -ne 0 ] || bad "$name: exit code 0"
  [ $rc -lt 128 ] || bad "$name: crashed (exit $rc)"
  lines=$(wc -l <"$WORK/stderr")
  [ "$lines" -eq 1 ] || bad "$name: $lines lines on stderr: $(cat "$WORK/stderr")"
  grep -q '^keygraph: ' "$WORK/stderr" || bad "$name: message does not start with 'keygraph: '"
  [ -z "$(ls -A "$WORK/case")" ] || bad "$name: left files behind: $(ls -A "$WORK/case")"
}

expect_failure "synth without -o" "$KG" synth
expect_failure "synth bad number" "$KG" synth -o out --frames many
expect_failure "synth too many signs" "$KG" synth -o out --signs 1000
expect_failure "synth no backgrounds" "$KG" synth -o out --backgrounds "$WORK/none"
expect_failure "synth frame size without --range" "$KG" synth -o out --size 1280x720
expect_failure "synth frame size of another camera" "$KG" synth -o out --range --size 640x640
expect_failure "synth bad frame size" "$KG" synth -o out --range --size 1280
expect_failure "synth bad JPEG quality" "$KG" synth -o out --jpeg 101
expect_failure "eval without input" "$KG" eval
expect_failure "eval both inputs" "$KG" eval --dataset a --synth b
expect_failure "eval missing synth dir" "$KG" eval --synth "$WORK/none"
mkdir -p "$WORK/corrupt" && echo "keygraph-synth 2" >"$WORK/corrupt/manifest.txt"
expect_failure "eval corrupt manifest" "$KG" eval --synth "$WORK/corrupt"
expect_failure "eval bad sizes" "$KG" eval --synth "$WORK/corrupt" --sizes 0
expect_failure "eval unknown option" "$KG" eval --synth "$WORK/corrupt" --bogus 1

# A small set, end to end.
"$KG" synth -o "$WORK/set" --signs 2 --frames 4 --seed 3 >/dev/null 2>"$WORK/stderr" ||
  bad "synth failed: $(cat "$WORK/stderr")"
[ -f "$WORK/set/manifest.txt" ] || bad "no manifest"
# Progress (stderr is no terminal here): plain lines, the last at 100 %.
grep -Eqx 'synth: frame 4/4 \(100 %\), took [0-9]+:[0-9]{2}' "$WORK/stderr" ||
  bad "synth: no final progress line: $(cat "$WORK/stderr")"
[ "$(ls "$WORK/set/frames" | wc -l)" -eq 4 ] || bad "expected 4 frames"
ls -A "$WORK" | grep -q '^\.tmp-' && bad "temporary directory left behind"
expect_failure "synth into a non-empty directory" "$KG" synth -o "$WORK/set"
[ -f "$WORK/set/manifest.txt" ] || bad "the existing set was damaged"
expect_failure "eval unknown method" "$KG" eval --synth "$WORK/set" --methods nonesuch
"$KG" eval --synth "$WORK/set" --sizes 1,2 --methods keygraph,orb-ransac --out "$WORK/out" \
  >"$WORK/stdout" 2>"$WORK/stderr" || bad "eval --synth failed: $(cat "$WORK/stderr")"
# 2 index sizes x 2 methods x 4 frames: 16 cases, a line per ~10 %.
grep -Eq '^eval: case 16/16 .* \(100 %\), took [0-9]+:[0-9]{2}$' "$WORK/stderr" &&
  grep -Eq '^eval: case 8/16 .* \(50 %\), [0-9]+:[0-9]{2} left$' "$WORK/stderr" ||
  bad "eval --synth: progress lines missing: $(cat "$WORK/stderr")"
grep -q '^orb-ransac  *2 ' "$WORK/stdout" || bad "no orb-ransac row for the index of 2: $(cat "$WORK/stdout")"
python3 -c "import json,sys; d=json.load(open(sys.argv[1])); assert len(d['results']) == 4" \
  "$WORK/out/synth-summary.json" || bad "synth-summary.json is not the expected JSON"
[ "$(wc -l <"$WORK/out/synth-cases.csv")" -eq 17 ] || bad "synth-cases.csv: expected 16 rows"
# Every row has as many fields as the header.
awk -F, 'NR==1 {n=NF} NF!=n {exit 1}' "$WORK/out/synth-cases.csv" ||
  bad "synth-cases.csv: rows and header disagree"

# The small-sign benchmark (issue 38): 1280x720 frames, distances, bins.
"$KG" synth -o "$WORK/range" --range --size 1280x720 --signs 2 --frames 3 --seed 3 \
  --jpeg 85 -q >/dev/null 2>"$WORK/stderr" || bad "synth --range failed: $(cat "$WORK/stderr")"
grep -q '^frame-size 1280 720$' "$WORK/range/manifest.txt" || bad "range set: not 1280x720"
grep -q ' distance [0-9.]* jpeg 85$' "$WORK/range/manifest.txt" ||
  bad "range set: no distance or JPEG quality in the manifest"
"$KG" eval --synth "$WORK/range" --sizes 2 --methods keygraph --out "$WORK/range-out" \
  >"$WORK/stdout" 2>"$WORK/stderr" || bad "eval --synth of a range set failed: $(cat "$WORK/stderr")"
grep -q "by the sign's long edge" "$WORK/stdout" && grep -q "by the sign's distance" "$WORK/stdout" ||
  bad "eval --synth: no long-edge or distance table: $(cat "$WORK/stdout")"
python3 -c "import json,sys; d=json.load(open(sys.argv[1])); assert d['by_distance_m']" \
  "$WORK/range-out/synth-summary.json" || bad "synth-summary.json: no bins by distance"

finish
