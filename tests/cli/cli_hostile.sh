#!/bin/bash
# Hostile and careless input for the keygraph CLI (issue 15), each case of
# the issue's table by its row number: no crash, no hang, no decompression
# bomb, no lost or clobbered file. Every failure must be exactly one
# "keygraph: " line on stderr and a non-zero exit, and leave its directory
# as it was (no file created, changed or left behind).
#
# usage: cli_hostile.sh KEYGRAPH DATA_DIR desktop|device [GOLDEN_INDEX]
#   desktop: the desktop keygraph (OpenCV); DATA_DIR is opencv-doc's data.
#   device:  the device keygraph (PGM only); GOLDEN_INDEX is an index built
#            with the core's detector (tests/data/golden-6.0-int8.kgi).
# The device-node case (row 8) and the permission case (row 14) need root
# (mknod, and setpriv to run as nobody); without root they are reported as
# SKIPPED, never silently passed.
set -u

KG=${1:?usage: cli_hostile.sh KEYGRAPH DATA_DIR desktop|device [GOLDEN_INDEX]}
DATA=${2:?usage}
MODE=${3:?usage}
GOLDEN=${4:-}
die() {
  echo "cli_hostile: $*" >&2
  exit 1
}
[ -x "$KG" ] || die "no keygraph binary at $KG"
[ "$MODE" = desktop ] || [ "$MODE" = device ] || die "mode must be desktop or device"
command -v python3 >/dev/null 2>&1 || die "python3 is needed to make test files"
KG=$(cd "$(dirname "$KG")" && pwd)/$(basename "$KG")
if [ -d "$DATA" ]; then DATA=$(cd "$DATA" && pwd); else [ "$MODE" = device ] || die "no $DATA"; fi

WORK=$(mktemp -d "${TMPDIR:-/tmp}/kg_hostile.XXXXXX") || die "mktemp failed"
PIDS=
cleanup() {
  for p in $PIDS; do kill "$p" 2>/dev/null; done
  rm -rf "$WORK"
}
trap cleanup EXIT
trap 'exit 1' HUP INT TERM
LOG=$WORK/log
mkdir "$LOG"

failures=0
checks=0
skipped=0
bad() {
  echo "FAIL: $*" >&2
  failures=$((failures + 1))
}
skip() {
  echo "SKIPPED: $*" >&2
  skipped=$((skipped + 1))
}

# Snapshot of a directory: names, types, sizes and checksums, so a changed
# or replaced file shows up as well as a new one.
snapshot() {
  (cd "$1" && find . -mindepth 1 -printf '%p %y %s\n' | sort &&
    find . -type f -exec cksum {} + 2>/dev/null | sort)
}

CASE=
next_case() {
  checks=$((checks + 1))
  CASE=$WORK/case$checks
  mkdir "$CASE"
}

# run_kg: the command with a time limit (a hang is a failure, not a stuck
# test); its exit status in $rc (124: timed out).
run_kg() {
  (cd "$CASE" && timeout 60 "$@") >"$LOG/stdout" 2>"$LOG/stderr"
  rc=$?
}

# expect_failure NAME NEEDLE CMD...: one stderr line containing NEEDLE
# (fixed string, may be empty), a non-zero exit, no crash or hang, and
# $CASE unchanged.
expect_failure() {
  name=$1
  needle=$2
  shift 2
  before=$(snapshot "$CASE")
  run_kg "$@"
  after=$(snapshot "$CASE")
  lines=$(wc -l <"$LOG/stderr" | tr -d ' ')
  if [ "$rc" -eq 0 ]; then
    bad "$name: exit status 0, expected a failure"
  elif [ "$rc" -eq 124 ]; then
    bad "$name: hung (killed after 60 s)"
  elif [ "$rc" -ge 128 ]; then
    bad "$name: killed by signal $((rc - 128))"
  fi
  if [ "$lines" -ne 1 ]; then
    bad "$name: expected one line on stderr, got $lines:"
    sed 's/^/    /' "$LOG/stderr" >&2
  elif ! grep -q '^keygraph: ' "$LOG/stderr"; then
    bad "$name: stderr line does not start with 'keygraph: ': $(cat "$LOG/stderr")"
  elif [ -n "$needle" ] && ! grep -qF -- "$needle" "$LOG/stderr"; then
    bad "$name: stderr lacks '$needle': $(cat "$LOG/stderr")"
  fi
  if [ "$before" != "$after" ]; then
    bad "$name: files created, changed or left behind:"
    diff <(echo "$before") <(echo "$after") | sed 's/^/    /' >&2
  fi
}

# expect_success NAME CMD...: exit 0, nothing on stderr.
expect_success() {
  name=$1
  shift
  run_kg "$@"
  if [ "$rc" -ne 0 ]; then
    bad "$name: exit $rc: $(cat "$LOG/stderr")"
  elif [ -s "$LOG/stderr" ]; then
    bad "$name: wrote to stderr: $(cat "$LOG/stderr")"
  fi
}

# --- inputs ------------------------------------------------------------------
IN=$WORK/in
mkdir "$IN"
# A PGM (P5) file: WIDTH HEIGHT [DECLARED_ONLY]. Texture: blocks and a
# gradient, so the detector finds keypoints; DECLARED_ONLY writes the header
# and only 100 bytes of pixels (a PGM bomb).
make_pgm() {
  python3 - "$@" <<'EOF'
import sys
path, w, h = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
declared_only = len(sys.argv) > 4
with open(path, "wb") as f:
    f.write(b"P5\n%d %d\n255\n" % (w, h))
    if declared_only:
        f.write(bytes(100))
    else:
        f.write(bytes(((x // 13 + y // 17) % 2) * 150 + (x + y) % 90
                      for y in range(h) for x in range(w)))
EOF
}
# A PNG of W x H, all black, compressed (a 16384x16384 one is 260 KB).
make_png_bomb() {
  python3 - "$@" <<'EOF'
import struct, sys, zlib
path, w, h = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
def chunk(kind, data):
    return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))
z = zlib.compressobj(9)
row = bytes(w + 1)
idat = b"".join(z.compress(row) for _ in range(h)) + z.flush()
with open(path, "wb") as f:
    f.write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 0, 0, 0, 0)) +
            chunk(b"IDAT", idat) + chunk(b"IEND", b""))
EOF
}
# A real JPEG whose frame header (SOF) declares W x H instead.
make_jpeg_declaring() {
  python3 - "$@" <<'EOF'
import struct, sys
src, dst, w, h = sys.argv[1], sys.argv[2], int(sys.argv[3]), int(sys.argv[4])
b = bytearray(open(src, "rb").read())
i = 2
while i + 4 <= len(b):
    assert b[i] == 0xFF
    marker, length = b[i + 1], struct.unpack(">H", b[i + 2:i + 4])[0]
    if marker in (0xC0, 0xC1, 0xC2):
        b[i + 5:i + 9] = struct.pack(">HH", h, w)
        break
    i += 2 + length
open(dst, "wb").write(b)
EOF
}

if [ "$MODE" = desktop ]; then
  for f in box.png box_in_scene.png fruits.jpg; do
    [ -f "$DATA/$f" ] || die "missing $DATA/$f (install Debian's opencv-doc package)"
  done
  EXT=png
  SCENE=$IN/scene.png
  cp "$DATA/box_in_scene.png" "$SCENE"
  INDEX=$IN/box.kgi
  "$KG" build "$DATA/box.png" -o "$INDEX" >/dev/null 2>"$LOG/stderr" ||
    die "keygraph build box.png failed: $(cat "$LOG/stderr")"
else
  [ -f "$GOLDEN" ] || die "device mode needs an index (tests/data/golden-6.0-int8.kgi)"
  EXT=pgm
  SCENE=$IN/scene.pgm
  make_pgm "$SCENE" 320 240
  INDEX=$IN/box.kgi
  cp "$GOLDEN" "$INDEX"
fi
"$KG" detect --index "$INDEX" "$SCENE" >/dev/null 2>"$LOG/stderr" ||
  die "keygraph detect on the test scene failed: $(cat "$LOG/stderr")"

# --- row 1: --roi whose X + W overflows an int ---------------------------------
if [ "$MODE" = desktop ]; then
  next_case
  expect_failure "row 1: build --roi X+W overflowing int" "lies outside" \
    "$KG" build --roi 2147483600,0,100,100 "$DATA/box.png" -o "$CASE/r.kgi"
  next_case
  expect_failure "row 1: build --roi Y+H overflowing int" "lies outside" \
    "$KG" build --roi 0,2147483600,100,100 "$DATA/box.png" -o "$CASE/r.kgi"
fi

# --- rows 2 and 3: decompression bombs, refused before decoding ---------------
# The message says "not decoded" (checked on the size the file declares);
# a check after decoding would say "too large" having spent gigabytes.
if [ "$MODE" = desktop ]; then
  make_png_bomb "$IN/bomb16k.png" 16384 16384
  make_png_bomb "$IN/bomb32k.png" 32768 32768
  make_jpeg_declaring "$DATA/fruits.jpg" "$IN/bomb.jpg" 30000 30000
  for bomb in bomb16k.png bomb32k.png bomb.jpg; do
    next_case
    cp "$IN/$bomb" "$CASE/"
    expect_failure "row 2: detect $bomb" "not decoded" "$KG" detect --index "$INDEX" "$CASE/$bomb"
    expect_failure "row 2: build $bomb" "not decoded" "$KG" build "$CASE/$bomb" -o "$CASE/b.kgi"
    expect_failure "row 3: bench $bomb" "not decoded" \
      "$KG" bench --index "$INDEX" --repeat 1 "$CASE/$bomb"
  done
fi
# PGM: the declared size is checked before the pixels are allocated.
next_case
make_pgm "$CASE/bomb.pgm" 16384 16384 declared_only
expect_failure "row 2: PGM declaring 16384x16384" "over 16777216 pixels" \
  "$KG" bench --index "$INDEX" --repeat 1 "$CASE/bomb.pgm"
if [ "$MODE" = device ]; then
  expect_failure "row 2: device detect, PGM bomb" "over 16777216 pixels" \
    "$KG" detect --index "$INDEX" "$CASE/bomb.pgm"
fi
# live: a bomb among good frames is a skipped frame, the run goes on.
next_case
mkdir "$CASE/frames"
cp "$SCENE" "$CASE/frames/a.$EXT"
make_pgm "$CASE/frames/b.pgm" 16384 16384 declared_only
[ "$MODE" = desktop ] && cp "$IN/bomb16k.png" "$CASE/frames/c.png"
run_kg "$KG" live --index "$INDEX" --images "$CASE/frames" --json
n=$(wc -l <"$LOG/stdout" | tr -d ' ')
if [ "$rc" -eq 0 ] || [ "$rc" -ge 124 ] || [ "$n" -ne 1 ] ||
  ! grep -q "frame skipped" "$LOG/stderr"; then
  bad "row 2: live with bombs among frames: exit $rc, $n frames: $(cat "$LOG/stderr")"
fi

# --- row 4: FIFOs never block ----------------------------------------------------
next_case
mkfifo "$CASE/f.kgi" "$CASE/f.$EXT"
expect_failure "row 4: inspect FIFO" "is a FIFO" "$KG" inspect "$CASE/f.kgi"
expect_failure "row 4: detect --index FIFO" "is a FIFO" "$KG" detect --index "$CASE/f.kgi" "$SCENE"
expect_failure "row 4: detect scene FIFO" "is a FIFO" "$KG" detect --index "$INDEX" "$CASE/f.$EXT"
expect_failure "row 4: bench --index FIFO" "is a FIFO" "$KG" bench --index "$CASE/f.kgi" "$SCENE"
expect_failure "row 4: bench frame FIFO" "is a FIFO" "$KG" bench --index "$INDEX" "$CASE/f.$EXT"
expect_failure "row 4: live --index FIFO" "is a FIFO" \
  "$KG" live --index "$CASE/f.kgi" --images "$SCENE"
if [ "$MODE" = desktop ]; then
  expect_failure "row 4: build model FIFO" "is a FIFO" "$KG" build "$CASE/f.png" -o "$CASE/o.kgi"
fi
run_kg "$KG" live --index "$INDEX" --images "$CASE/f.$EXT"
if [ "$rc" -eq 0 ] || [ "$rc" -ge 124 ] || ! grep -q "is a FIFO" "$LOG/stderr"; then
  bad "row 4: live --images FIFO: exit $rc: $(cat "$LOG/stderr")"
fi

# --- row 5: a looping source of unreadable files ends --------------------------
next_case
mkdir "$CASE/allbad"
echo "not an image" >"$CASE/allbad/a.$EXT"
echo "not an image either" >"$CASE/allbad/b.pgm"
run_kg "$KG" live --index "$INDEX" --images "$CASE/allbad" --loop --frames 3
if [ "$rc" -eq 0 ] || [ "$rc" -ge 124 ] ||
  ! grep -q "none of the 2 image files could be read" "$LOG/stderr"; then
  bad "row 5: live --loop over unreadable files: exit $rc: $(tail -n 3 "$LOG/stderr")"
fi

# --- rows 6 and 7: interrupted and concurrent builds ------------------------------
if [ "$MODE" = desktop ]; then
  # Several large models: the build runs for seconds, with its temporary
  # output created at the start.
  MODELS=()
  for i in 1 2 3 4 5 6; do
    cp "$DATA/box_in_scene.png" "$IN/model$i.png"
    MODELS+=("$IN/model$i.png")
  done
  for sig in INT TERM; do
    next_case
    before=$(snapshot "$CASE")
    # A shell starts background commands with SIGINT ignored; restore it.
    (cd "$CASE" && exec python3 -c 'import os, signal, sys
signal.signal(signal.SIGINT, signal.SIG_DFL)
os.execv(sys.argv[1], sys.argv[1:])' "$KG" build "${MODELS[@]}" -o "$CASE/w.kgi") \
      >"$LOG/stdout" 2>"$LOG/stderr" &
    pid=$!
    PIDS="$PIDS $pid"
    tmp=
    for _ in $(seq 1 300); do
      tmp=$(find "$CASE" -name '.w.kgi.*' | head -n 1)
      [ -n "$tmp" ] && break
      sleep 0.05
    done
    [ -n "$tmp" ] || bad "row 6: build never created its temporary output"
    kill -s "$sig" "$pid"
    wait "$pid"
    rc=$?
    after=$(snapshot "$CASE")
    [ "$rc" -ge 128 ] || bad "row 6: SIG$sig during build: exit $rc, expected death by the signal"
    [ "$before" = "$after" ] || bad "row 6: SIG$sig during build left: $(ls -A "$CASE")"
  done

  # A user's own OUT.kgi.tmp is neither overwritten nor deleted.
  next_case
  echo "my notes" >"$CASE/p.kgi.tmp"
  run_kg "$KG" build "$DATA/box.png" -o "$CASE/p.kgi"
  [ "$rc" -eq 0 ] || bad "row 7: build next to p.kgi.tmp failed: $(cat "$LOG/stderr")"
  [ "$(cat "$CASE/p.kgi.tmp" 2>/dev/null)" = "my notes" ] || bad "row 7: the user's p.kgi.tmp was changed"
  # Two builds to one -o at once: each writes its own temporary; both
  # succeed and the index is one of the two, whole.
  next_case
  (cd "$CASE" && "$KG" build --name alpha "${MODELS[@]:0:3}" -o p.kgi) >"$LOG/a.out" 2>"$LOG/a.err" &
  a=$!
  (cd "$CASE" && "$KG" build --name bravo "${MODELS[@]:0:3}" -o p.kgi) >"$LOG/b.out" 2>"$LOG/b.err" &
  b=$!
  PIDS="$PIDS $a $b"
  wait "$a"
  ra=$?
  wait "$b"
  rb=$?
  [ "$ra" -eq 0 ] && [ "$rb" -eq 0 ] || bad "row 7: concurrent builds: exit $ra and $rb"
  [ "$(ls -A "$CASE")" = "p.kgi" ] || bad "row 7: concurrent builds left: $(ls -A "$CASE")"
  if "$KG" inspect "$CASE/p.kgi" >"$LOG/stdout" 2>"$LOG/stderr"; then
    names=$(grep -Eo ' (alpha|bravo) ' "$LOG/stdout" | tr -d ' ' | sort -u | tr '\n' ' ')
    [ "$names" = "alpha " ] || [ "$names" = "bravo " ] ||
      bad "row 7: concurrent builds: index holds models '$names'"
  else
    bad "row 7: concurrent builds left an index that does not load: $(cat "$LOG/stderr")"
  fi
fi

# --- row 8: outputs never replace a device node ------------------------------------
if [ "$(id -u)" -eq 0 ]; then
  next_case
  mknod "$CASE/n" c 1 3
  mknod "$CASE/n.$EXT" c 1 3
  mknod "$CASE/n.pgm" c 1 3 2>/dev/null
  if [ "$MODE" = desktop ]; then
    expect_failure "row 8: build -o device node" "is a character device" \
      "$KG" build "$DATA/box.png" -o "$CASE/n"
  fi
  expect_failure "row 8: detect --draw device node" "is a character device" \
    "$KG" detect --index "$INDEX" --draw "$CASE/n.$EXT" "$SCENE"
  [ -c "$CASE/n" ] && [ -c "$CASE/n.$EXT" ] || bad "row 8: a device node was replaced"
else
  skip "row 8: outputs onto a device node (mknod needs root)"
fi

# --- row 9: an output that is an input -------------------------------------------
next_case
cp "$SCENE" "$CASE/s.$EXT"
expect_failure "row 9: detect --draw onto its scene" "is also an input" \
  "$KG" detect --index "$INDEX" --draw "$CASE/s.$EXT" "$CASE/s.$EXT"
cp "$INDEX" "$CASE/i.kgi"
ln -s s.$EXT "$CASE/link.$EXT"
expect_failure "row 9: detect --draw onto a link to its scene" "is also an input" \
  "$KG" detect --index "$CASE/i.kgi" --draw "$CASE/link.$EXT" "$CASE/s.$EXT"
if [ "$MODE" = desktop ]; then
  cp "$DATA/box.png" "$CASE/a.png"
  expect_failure "row 9: build -o onto its model image" "is also an input" \
    "$KG" build "$CASE/a.png" -o "$CASE/a.png"
fi

# --- row 10: two scenes with one stem ----------------------------------------------
next_case
mkdir "$CASE/a" "$CASE/b"
cp "$SCENE" "$CASE/a/x.$EXT"
cp "$SCENE" "$CASE/b/x.$EXT"
expect_failure "row 10: detect --draw, scenes with one stem" "would both be drawn to" \
  "$KG" detect --index "$INDEX" --draw "$CASE/ms.$EXT" "$CASE/a/x.$EXT" "$CASE/b/x.$EXT"
next_case
mkdir "$CASE/frames" "$CASE/drawn"
cp "$SCENE" "$CASE/frames/x.$EXT"
if [ "$MODE" = desktop ]; then make_pgm "$CASE/frames/x.pgm" 64 48; else cp "$SCENE" "$CASE/frames/x.PGM"; fi
expect_failure "row 10: live --draw, images with one stem" "would both be drawn to" \
  "$KG" live --index "$INDEX" --images "$CASE/frames" --draw "$CASE/drawn"

# --- row 11: truncated JPEGs are errors --------------------------------------------
if [ "$MODE" = desktop ]; then
  for jpeg in fruits.jpg leuvenA.jpg; do
    size=$(wc -c <"$DATA/$jpeg" | tr -d ' ')
    for pct in 10 50 90; do
      next_case
      head -c $((size * pct / 100)) "$DATA/$jpeg" >"$CASE/t.jpg"
      expect_failure "row 11: detect $jpeg cut at $pct %" "truncated JPEG" \
        "$KG" detect --index "$INDEX" "$CASE/t.jpg"
      expect_failure "row 11: build $jpeg cut at $pct %" "truncated JPEG" \
        "$KG" build "$CASE/t.jpg" -o "$CASE/t.kgi"
      expect_failure "row 11: bench $jpeg cut at $pct %" "truncated JPEG" \
        "$KG" bench --index "$INDEX" --repeat 1 "$CASE/t.jpg"
    done
  done
  # The whole files still load (no false alarm on thumbnails or padding).
  next_case
  for jpeg in "$DATA"/*.jpg; do
    run_kg "$KG" detect --index "$INDEX" "$jpeg"
    [ "$rc" -eq 0 ] || bad "row 11: whole JPEG $jpeg refused: $(cat "$LOG/stderr")"
  done
fi

# --- row 12: the index changed in place while in use ------------------------------
# Two indexes of one size whose model names differ (aaaa, bbbb): a process
# that mapped the first would see the second's name after `cp` over it, or
# die of SIGBUS after `truncate`. The commands read the index into memory.
next_case
if [ "$MODE" = desktop ]; then
  "$KG" build --name aaaa "$DATA/box.png" -o "$IN/aaaa.kgi" >/dev/null
  "$KG" build --name bbbb "$DATA/box.png" -o "$IN/bbbb.kgi" >/dev/null
else
  cp "$INDEX" "$IN/aaaa.kgi"
  cp "$INDEX" "$IN/bbbb.kgi"
fi
SCENES=()
for i in $(seq 1 40); do SCENES+=("$SCENE"); done
for change in truncate cp; do
  cp "$IN/aaaa.kgi" "$CASE/ip.kgi"
  : >"$LOG/ip.out"
  (cd "$CASE" && exec "$KG" detect --index ip.kgi "${SCENES[@]}") >"$LOG/ip.out" 2>"$LOG/stderr" &
  pid=$!
  PIDS="$PIDS $pid"
  # The first scene's line: the index is loaded.
  for _ in $(seq 1 600); do
    [ -s "$LOG/ip.out" ] && break
    sleep 0.05
  done
  if [ "$change" = truncate ]; then
    truncate -s 0 "$CASE/ip.kgi"
  else
    cp "$IN/bbbb.kgi" "$CASE/ip.kgi" # in place: same inode
  fi
  wait "$pid"
  rc=$?
  n=$(grep -c 'detection(s)' "$LOG/ip.out")
  [ "$rc" -eq 0 ] && [ "$n" -eq 40 ] ||
    bad "row 12: detect while the index is changed in place ($change): exit $rc, $n of 40 scenes"
  if [ "$MODE" = desktop ] && grep -q bbbb "$LOG/ip.out"; then
    bad "row 12: detect switched to the other index's model names after $change"
  fi
done

# live reloads an index that changed (rename, in-place copy), keeps the
# loaded one while the file does not load, and never dies of it.
next_case
mkdir "$CASE/frames"
cp "$SCENE" "$CASE/frames/s.$EXT"
cp "$IN/aaaa.kgi" "$CASE/live.kgi"
(cd "$CASE" && exec "$KG" live --index live.kgi --images frames --loop --json) \
  >"$LOG/live.out" 2>"$LOG/live.err" &
live=$!
PIDS="$PIDS $live"
# wait_for FILE PATTERN: up to 30 s for a line matching PATTERN.
wait_for() {
  for _ in $(seq 1 600); do
    grep -q -- "$2" "$1" && return 0
    sleep 0.05
  done
  return 1
}
reloads() { grep -c 'changed: reloaded' "$LOG/live.err"; }
wait_for "$LOG/live.out" '"scene"' || bad "row 12: live produced no frame"
cp "$IN/bbbb.kgi" "$CASE/new.kgi"
mv "$CASE/new.kgi" "$CASE/live.kgi"
wait_for "$LOG/live.err" 'changed: reloaded' || bad "row 12: live did not reload a renamed index"
truncate -s 0 "$CASE/live.kgi"
wait_for "$LOG/live.err" 'index changed but not reloaded' ||
  bad "row 12: live did not report an index it could not reload"
cp "$IN/aaaa.kgi" "$CASE/live.kgi"
for _ in $(seq 1 600); do
  [ "$(reloads)" -ge 2 ] && break
  sleep 0.05
done
[ "$(reloads)" -eq 2 ] || bad "row 12: live reloaded $(reloads) times, expected 2"
[ "$(grep -c 'not reloaded' "$LOG/live.err")" -eq 1 ] ||
  bad "row 12: live reported the index it could not load $(grep -c 'not reloaded' "$LOG/live.err") times, expected once"
kill -INT "$live"
wait "$live"
rc=$?
[ "$rc" -eq 0 ] || bad "row 12: live with index changes: exit $rc: $(tail -n 3 "$LOG/live.err")"
if [ "$MODE" = desktop ]; then
  # The detections name the model of the index loaded at the time.
  models=$(grep -o '"model": "[a-z]*"' "$LOG/live.out" | uniq | sed 's/.*: "//; s/"//' | tr '\n' ' ')
  case "$models" in
    "aaaa bbbb aaaa ") ;;
    *) bad "row 12: live's detections named '$models', expected 'aaaa bbbb aaaa '" ;;
  esac
fi

# --- row 13: output lost on stdout is an error ----------------------------------------
if [ -w /dev/full ]; then
  next_case
  full() {
    name=$1
    shift
    (cd "$CASE" && timeout 60 "$@") >/dev/full 2>"$LOG/stderr"
    rc=$?
    if [ "$rc" -eq 0 ] || [ "$rc" -ge 124 ] || [ "$(wc -l <"$LOG/stderr")" -ne 1 ] ||
      ! grep -Eq '^keygraph: ([a-z]+: )?cannot write to stdout' "$LOG/stderr"; then
      bad "row 13: $name > /dev/full: exit $rc: $(cat "$LOG/stderr")"
    fi
  }
  full "detect --json" "$KG" detect --index "$INDEX" --json "$SCENE"
  full "detect" "$KG" detect --index "$INDEX" "$SCENE"
  full "inspect" "$KG" inspect "$INDEX"
  full "bench" "$KG" bench --index "$INDEX" --repeat 2 "$SCENE"
  full "help" "$KG" help
  [ "$MODE" = desktop ] && full "build" "$KG" build --quiet "$DATA/box.png" -o "$CASE/full.kgi"
  rm -f "$CASE/full.kgi"
else
  skip "row 13: no writable /dev/full"
fi

# --- row 14: errors that say what happened -------------------------------------------
next_case
mkdir "$CASE/d.$EXT"
mkfifo "$CASE/f.$EXT"
ln -s loop1.$EXT "$CASE/loop2.$EXT"
ln -s loop2.$EXT "$CASE/loop1.$EXT"
# A directory is a set of scenes (issue 39): an empty one says so.
expect_failure "row 14: empty directory as scene" "d.$EXT: a directory with no image files" \
  "$KG" detect --index "$INDEX" "$CASE/d.$EXT"
expect_failure "row 14: FIFO as scene" "f.$EXT: is a FIFO" \
  "$KG" detect --index "$INDEX" "$CASE/f.$EXT"
expect_failure "row 14: /dev/zero as scene" "/dev/zero: is a character device" \
  "$KG" detect --index "$INDEX" /dev/zero
expect_failure "row 14: symlink loop as scene" "too many levels of symbolic links" \
  "$KG" detect --index "$INDEX" "$CASE/loop1.$EXT"
expect_failure "row 14: symlink loop as index" "too many levels of symbolic links" \
  "$KG" detect --index "$CASE/loop1.$EXT" "$SCENE"
expect_failure "row 14: directory as index" "is a directory" \
  "$KG" inspect "$CASE/d.$EXT"
# Permission denied on the index: as root, run as nobody (root reads
# anything); otherwise a file without read permission.
next_case
cp "$INDEX" "$CASE/secret.kgi"
chmod 000 "$CASE/secret.kgi"
chmod 755 "$CASE" "$WORK"
if [ "$(id -u)" -ne 0 ]; then
  expect_failure "row 14: unreadable index" "permission denied" "$KG" inspect "$CASE/secret.kgi"
elif command -v setpriv >/dev/null 2>&1 && [ -x "$KG" ] &&
  setpriv --reuid=nobody --regid=nogroup --clear-groups true 2>/dev/null &&
  setpriv --reuid=nobody --regid=nogroup --clear-groups test -x "$KG"; then
  expect_failure "row 14: unreadable index (as nobody)" "permission denied" \
    setpriv --reuid=nobody --regid=nogroup --clear-groups "$KG" inspect "$CASE/secret.kgi"
  expect_failure "row 14: unreadable index, detect (as nobody)" "permission denied" \
    setpriv --reuid=nobody --regid=nogroup --clear-groups "$KG" detect --index "$CASE/secret.kgi" \
    "$SCENE"
else
  skip "row 14: permission denied (root without setpriv, or keygraph not executable by nobody)"
fi
# Random bytes after the magic: damage, not "a newer keygraph".
next_case
python3 - "$INDEX" "$CASE/random.kgi" <<'EOF'
import random, sys
b = bytearray(open(sys.argv[1], "rb").read())
rng = random.Random(15)
for i in range(8, len(b)):
    b[i] = rng.randrange(256)
b[8:12] = bytes([0x76, 0xE2, 0x6A, 0x81])  # version 57974.33130, as in the report
open(sys.argv[2], "wb").write(b)
EOF
expect_failure "row 14: random bytes after the magic" "header: damaged" \
  "$KG" inspect "$CASE/random.kgi"
grep -q newer "$LOG/stderr" && bad "row 14: random bytes reported as a newer version"
next_case
expect_failure "row 14: --frames over the limit" "not a count in 1..1073741824" \
  "$KG" live --index "$INDEX" --images "$SCENE" --frames 999999999999
if [ "$MODE" = desktop ]; then
  expect_failure "row 14: demo --out without a value" "demo: --out needs a value" "$KG" demo --out
fi
# A frame over the detector's limit (20000 pixels wide) is skipped with a
# warning; the other frames are measured.
next_case
mkdir "$CASE/frames"
cp "$SCENE" "$CASE/frames/a.$EXT"
make_pgm "$CASE/frames/wide.pgm" 20000 8
run_kg "$KG" bench --index "$INDEX" --repeat 2 --json "$CASE/frames"
if [ "$rc" -ne 0 ] || [ "$(wc -l <"$LOG/stdout")" -ne 1 ] ||
  ! grep -q "wide.pgm: frame 20000x8 is beyond the detector's limits" "$LOG/stderr"; then
  bad "row 14: bench with a frame over the limits: exit $rc: $(cat "$LOG/stderr")"
fi
run_kg "$KG" live --index "$INDEX" --images "$CASE/frames" --json
if [ "$rc" -ge 124 ] || [ "$(wc -l <"$LOG/stdout")" -ne 1 ] ||
  ! grep -q "wide.pgm: frame 20000x8 is beyond the detector's limits" "$LOG/stderr" ||
  ! grep -q "1 frame in .*1 bad frame skipped" "$LOG/stderr"; then
  bad "row 14: live with a frame over the limits: exit $rc: $(cat "$LOG/stderr")"
fi
# Only frames over the limit, looping: the run ends instead of spinning.
mkdir "$CASE/wide"
mv "$CASE/frames/wide.pgm" "$CASE/wide/"
run_kg "$KG" live --index "$INDEX" --images "$CASE/wide" --loop
if [ "$rc" -eq 0 ] || [ "$rc" -ge 124 ] ||
  ! grep -q "none of the 1 image files is within the detector's limits" "$LOG/stderr"; then
  bad "row 14: live --loop over a frame over the limits: exit $rc: $(tail -n 2 "$LOG/stderr")"
fi
# Decoder library lines (libpng) do not come before keygraph's one line.
if [ "$MODE" = desktop ]; then
  next_case
  python3 - "$DATA/box.png" "$CASE/crc.png" <<'EOF'
import sys
b = bytearray(open(sys.argv[1], "rb").read())
i = b.find(b"IDAT")
b[i + 40] ^= 0xFF  # inside the first IDAT chunk: its CRC no longer matches
open(sys.argv[2], "wb").write(b)
EOF
  expect_failure "row 14: PNG with a bad CRC, detect" "" "$KG" detect --index "$INDEX" "$CASE/crc.png"
  expect_failure "row 14: PNG with a bad CRC, bench" "" \
    "$KG" bench --index "$INDEX" --repeat 1 "$CASE/crc.png"
fi

if [ "$failures" -ne 0 ]; then
  echo "cli_hostile ($MODE): $failures failure(s) in $checks checks, $skipped skipped" >&2
  exit 1
fi
echo "cli_hostile ($MODE): all $checks checks passed, $skipped skipped"
