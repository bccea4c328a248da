#!/usr/bin/env python3
"""The keygraph tool on the golden frames, desktop or device build alike.

The stored index of box.png (tests/data/frames-box.kgi) and PGM frames
made at build time (tests/tools/png_to_pgm.py): `detect --json` finds the
box in each frame with its corners within half a pixel of the stored ones
(tests/data/frames-corners.txt, the x86-64 reference that
tests/core/test_golden_frames.cpp holds the library to), `live --images`
gives one JSON line per frame with the box in each, and `inspect` reads the
index. With --libcamera, `live --libcamera` on a machine without a camera
(CI, qemu-user) stops with one stderr line naming the problem and a
non-zero exit. In the cross-builds KEYGRAPH is run under qemu-user: the
command after `--` is the emulator and the tool.

usage: cli_golden_frames.py INDEX FRAMES_DIR EXPECTED [--libcamera] -- KEYGRAPH...
"""
import json
import os
import subprocess
import sys

from cli_support import Checks, run_tool

TOLERANCE = 0.5  # pixels: other targets' floating point differs in the last bits

args = sys.argv[1:]
if "--" not in args or args.index("--") < 3:
    sys.exit(__doc__.strip().splitlines()[-1])
split = args.index("--")
INDEX, FRAMES, EXPECTED = args[:3]
LIBCAMERA = "--libcamera" in args[3:split]
KG = args[split + 1 :]
check = Checks("cli_golden_frames", verbose=True)


def run(*command, timeout=300):
    return run_tool(KG, *command, timeout=timeout)


def read_expected(path):
    """{frame: (model, [[x, y] * 4])} of frames-corners.txt."""
    out = {}
    with open(path) as f:
        for line in f:
            if line.strip() and not line.startswith("#"):
                fields = line.split()
                numbers = [float(v) for v in fields[2:10]]
                out[fields[0]] = (fields[1], [numbers[i : i + 2] for i in range(0, 8, 2)])
    return out


expected = read_expected(EXPECTED)
frames = sorted(expected)
paths = [os.path.join(FRAMES, f) for f in frames]
check(
    sorted(os.listdir(FRAMES)) == frames,
    f"the frames directory holds the stored frames only: {sorted(os.listdir(FRAMES))}",
)

# detect --json: the box at the stored corners.
result = run("detect", "--index", INDEX, "--json", *paths)
check(result.returncode == 0, f"detect exits 0 (got {result.returncode}: {result.stderr.strip()})")
records = [json.loads(line) for line in result.stdout.splitlines()] if result.returncode == 0 else []
check(len(records) == len(frames), f"detect gives one JSON line per frame ({len(records)})")
for frame, record in zip(frames, records):
    model, corners = expected[frame]
    found = record["detections"]
    models = [d["model"] for d in found]
    check(models == [model], f"{frame}: {model} found once (found: {models})")
    if len(found) == 1:
        error = max(
            abs(a - b) for got, want in zip(found[0]["corners"], corners) for a, b in zip(got, want)
        )
        check(error <= TOLERANCE, f"{frame}: corners within {error:.2g} px of the stored ones")

# live --images: the same frames as a stream.
result = run("live", "--index", INDEX, "--images", FRAMES, "--json")
lines = result.stdout.splitlines()
counts = [len(json.loads(line)["detections"]) for line in lines] if result.returncode == 0 else []
check(
    result.returncode == 0 and counts == [1] * len(frames),
    f"live --images: {len(frames)} frames, one detection in each (exit {result.returncode}, {counts})",
)

# inspect: the index's summary.
result = run("inspect", INDEX)
totals = [line for line in result.stdout.splitlines() if line.startswith("total:")]
check(result.returncode == 0 and len(totals) == 1, f"inspect: {totals}")

# live --libcamera without a camera: one line, a non-zero exit, no output.
if LIBCAMERA:
    try:
        result = run("live", "--index", INDEX, "--libcamera", timeout=120)
        errors = result.stderr.splitlines()
        check(
            result.returncode != 0
            and len(errors) == 1
            and "libcamera" in errors[0]
            and not result.stdout,
            f"live --libcamera without a camera: exit {result.returncode}, stderr {errors}",
        )
    except subprocess.TimeoutExpired:
        check(False, "live --libcamera without a camera: still running after 120 s")

check.finish()
