#!/bin/sh
# keygraph's help and usage errors (issue 16): every command answers
# --help, -h and `keygraph help CMD` on stdout with exit 0, listing its
# options (with defaults) and an example; every option its help lists is
# one its parser knows (tried one by one: never "unknown option"), and the
# options each command is known to have are all listed. An unknown option
# names itself and points to --help, exit 2; other usage errors exit 2;
# runtime failures exit 1.
#
# usage: cli_help.sh PATH/TO/keygraph desktop|device
set -u

KG=${1:?usage: cli_help.sh KEYGRAPH_BINARY desktop|device}
BUILD=${2:?usage: cli_help.sh KEYGRAPH_BINARY desktop|device}

[ -x "$KG" ] || {
  echo "cli_help: no keygraph binary at $KG" >&2
  exit 1
}
WORK=$(mktemp -d "${TMPDIR:-/tmp}/kg_help.XXXXXX") || exit 1
trap 'rm -rf "$WORK"' EXIT
trap 'exit 1' HUP INT TERM

failures=0
bad() {
  echo "FAIL: $*" >&2
  failures=$((failures + 1))
}

# run CMD...: stdout, stderr and exit status in $WORK/out, $WORK/err, $rc.
run() {
  "$@" >"$WORK/out" 2>"$WORK/err"
  rc=$?
}

# The options each command is known to have (a lost option fails here even
# if the help and the parser lost it together).
known_options() {
  case $1 in
    build) echo "-o --out --output --name --roi --detector --structure --vertex-descriptor
                 --encoding --min-size --max-tilt --max-scale --set --max-side --draw-model
                 --no-look-alikes -j --jobs -q --quiet" ;;
    detect) echo "--index --json --draw" ;;
    demo) echo "-o --out --output --data" ;;
    eval) echo "--dataset --subsets --crops --size --centre --seed --set --methods --negatives
                --curves -o --out --output --csv --synth --sizes --frames --truth --models --index
                --tolerance --gallery --video --detect-interval --json -q --quiet" ;;
    manifest) echo "-o --out --output --split" ;;
    synth) echo "-o --out --output --seed --signs --frames --sign-free --range --jpeg --backgrounds --video --size
                 --exposure -q --quiet" ;;
    repeatability) echo "--dataset --subsets --detectors --set --max-keypoints --tolerance --csv
                         -q --quiet" ;;
    live) echo "--index --v4l2 --libcamera --images --size --loop --json --draw --frames -q --quiet" ;;
    bench) echo "--index --repeat --json" ;;
    inspect) echo "" ;;
  esac
}
desktop_only="build demo eval manifest synth repeatability"

# --- keygraph's own help ----------------------------------------------------
for h in --help -h help; do
  run "$KG" $h
  [ "$rc" -eq 0 ] && [ -s "$WORK/out" ] && [ ! -s "$WORK/err" ] ||
    bad "keygraph $h: exit $rc, expected the command list on stdout and exit 0"
done
run "$KG" --help
commands=$(sed -n '/^commands:/,/^$/p' "$WORK/out" | awk 'NF > 1 && $1 != "help" {print $1}')
for c in build detect demo eval manifest synth repeatability live bench inspect; do
  echo "$commands" | grep -qx "$c" || bad "keygraph --help does not list $c"
done
run "$KG"
[ "$rc" -eq 2 ] && [ ! -s "$WORK/out" ] || bad "keygraph without a command: exit $rc, expected 2"
run "$KG" frobnicate
[ "$rc" -eq 2 ] && grep -q "unknown command 'frobnicate'.*--help" "$WORK/err" ||
  bad "keygraph frobnicate: exit $rc, $(cat "$WORK/err")"
run "$KG" help frobnicate
[ "$rc" -eq 2 ] && grep -q "unknown command 'frobnicate'" "$WORK/err" ||
  bad "keygraph help frobnicate: exit $rc, $(cat "$WORK/err")"

# --- each command's help ----------------------------------------------------
for c in $commands; do
  if [ "$BUILD" = device ] && echo "$desktop_only" | grep -qw "$c"; then
    run "$KG" "$c" --help
    [ "$rc" -eq 1 ] && grep -q "not in this build" "$WORK/err" ||
      bad "device $c --help: exit $rc, expected 'not in this build' and exit 1"
    continue
  fi
  run "$KG" "$c" --help
  if [ "$rc" -ne 0 ] || [ -s "$WORK/err" ]; then
    bad "$c --help: exit $rc, stderr: $(cat "$WORK/err")"
    continue
  fi
  cp "$WORK/out" "$WORK/help"
  grep -q "^usage: keygraph $c " "$WORK/help" || bad "$c --help: no 'usage: keygraph $c' line"
  grep -q "^example" "$WORK/help" || bad "$c --help: no example"
  grep -q "^  -h, --help " "$WORK/help" || bad "$c --help: does not list -h, --help"
  for other in "$KG $c -h" "$KG help $c" "$KG $c --bogus-option --help"; do
    run $other
    [ "$rc" -eq 0 ] && cmp -s "$WORK/out" "$WORK/help" ||
      bad "'$other': exit $rc or output differs from '$c --help'"
  done
  # The options the help lists: the first column of its option rows.
  listed=$(grep -E '^  -' "$WORK/help" | awk '{for (i = 1; i <= NF; i++) { print $i; if ($i !~ /,$/) break }}' |
    tr -d ',' | grep -v -e '^-h$' -e '^--help$' | sort -u)
  for o in $(known_options "$c"); do
    echo "$listed" | grep -qx -- "$o" || bad "$c --help does not list $o"
  done
  # Every listed option is known to the parser. eval's modes each have
  # their own table: an option is tried in the mode whose help lists it.
  mode=
  grep -E '^(usage: keygraph|  -)' "$WORK/help" | while read -r first second rest; do
    if [ "$first" = "usage:" ]; then
      mode=$(echo "$rest" | awk '$2 ~ /^--(synth|truth|dataset|video)$/ {print $2}')
      continue
    fi
    # The row's names: "-o, --out, --output DIR" gives -o --out --output.
    names=$(echo "$first $second $rest" | awk '{for (i = 1; i <= NF; i++) { print $i; if ($i !~ /,$/) break }}')
    for o in $names; do
      case $o in -*) ;; *) continue ;; esac
      o=${o%,}
      [ "$o" = -h ] || [ "$o" = --help ] && continue
      if [ -n "$mode" ] && [ "$o" != "$mode" ]; then
        run "$KG" "$c" "$mode" "$WORK/none" "$o"
      else
        run "$KG" "$c" "$o"
      fi
      if grep -q "unknown option" "$WORK/err"; then
        echo "FAIL: $c lists $o ${mode:+(with $mode) }but rejects it: $(cat "$WORK/err")" >&2
        echo x >>"$WORK/unknown"
      fi
    done
  done
  # An option with a default shows it.
  tr '\n' ' ' <"$WORK/help" | grep -Eq 'default: [^)]+\)' || [ "$c" = inspect ] || [ "$c" = detect ] ||
    [ "$c" = manifest ] ||
    bad "$c --help shows no default"
  # An unknown option: named, pointing to --help, exit 2, nothing on stdout.
  run "$KG" "$c" --bogus-option
  if [ "$rc" -ne 2 ] || [ -s "$WORK/out" ] || [ "$(wc -l <"$WORK/err")" -ne 1 ] ||
    ! grep -q "^keygraph: $c: unknown option --bogus-option (see keygraph $c --help)$" "$WORK/err"; then
    bad "$c --bogus-option: exit $rc, stderr: $(cat "$WORK/err")"
  fi
done
[ -f "$WORK/unknown" ] && failures=$((failures + $(wc -l <"$WORK/unknown")))

# --- usage errors exit 2, runtime failures 1 --------------------------------
# expect_exit CODE NEEDLE CMD...: the exit code and one stderr line with NEEDLE.
expect_exit() {
  code=$1 needle=$2
  shift 2
  run "$@"
  [ "$rc" -eq "$code" ] && [ "$(wc -l <"$WORK/err")" -eq 1 ] && grep -qF -- "$needle" "$WORK/err" ||
    bad "'$*': exit $rc (expected $code), stderr: $(cat "$WORK/err")"
}
expect_exit 2 "bench: --repeat needs a value" "$KG" bench --index x.kgi f.pgm --repeat
expect_exit 2 "bench: --repeat 0: not a whole number in 1..1000000" \
  "$KG" bench --index x.kgi --repeat 0 f.pgm
expect_exit 2 "bench: --repeat 5x: not a whole number" "$KG" bench --index x.kgi --repeat 5x f.pgm
expect_exit 2 "live: give one source" "$KG" live --index x.kgi --images a --v4l2 /dev/video0
expect_exit 2 "inspect: no index given" "$KG" inspect
expect_exit 1 "$WORK/none.kgi" "$KG" inspect "$WORK/none.kgi"
if [ "$BUILD" = desktop ]; then
  expect_exit 2 "build: no model images given" "$KG" build -o "$WORK/x.kgi"
  expect_exit 2 "build: --roi must come before the model image" "$KG" build a.png --roi 0,0,5,5
  expect_exit 2 "build: unknown detector 'sift'" "$KG" build --detector sift a.png
  expect_exit 2 "eval: --crops 3x: not a whole number" "$KG" eval --dataset "$WORK" --crops 3x
  expect_exit 2 "eval: --tolerance 0: not a number in (0, 1000000]" \
    "$KG" eval --truth m.jsonl --tolerance 0
  expect_exit 2 "synth: --sign-free 1.5: not a number in [0, 1]" "$KG" synth -o d --sign-free 1.5
  expect_exit 2 "eval: unknown option --sizes (see keygraph eval --help)" \
    "$KG" eval --dataset "$WORK" --sizes 1
  expect_exit 1 "$WORK/none.png" "$KG" build "$WORK/none.png" -o "$WORK/x.kgi"
fi

if [ "$failures" -ne 0 ]; then
  echo "cli_help: $failures failure(s)" >&2
  exit 1
fi
echo "cli_help: all checks passed"
