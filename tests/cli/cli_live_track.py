#!/usr/bin/env python3
"""keygraph live tracks by default (issue 36), end to end on image files.

A camera pan made from a real photo: 12 crops of opencv-doc's box_in_scene,
each 3 px right and 2 px down from the one before, written as PGM frames
whose names sort differently from the order they were written in. Checked:
- live --images reads the frames in name order;
- with tracking (the default): the box on every frame with one track id,
  detection on the first frame and tracked (confirmed, no detection) frames
  after it, the corners following the pan as detection alone finds them,
  the stats of a frame without detection all zero, the text output's track,
  and a summary that counts the tracked and the detected frames;
- with --no-track: no frame tracked, every frame detected, the same box on
  every frame, no track ids;
- an index without model appearances: one line on stderr saying every
  frame is detected, exit 0, no frame tracked.

usage: cli_live_track.py KEYGRAPH KG_TO_PGM OPENCV_DATA_DIR
"""
import os
import re
import shutil
import subprocess
import sys
import tempfile

from cli_support import Checks, json_lines, read_pgm, run_tool, write_pgm_crop

KG, TO_PGM, DATA = (os.path.abspath(a) for a in sys.argv[1:4])
FRAMES = 12
STEP = (3, 2)  # pixels the camera pans per frame (the box moves by minus this)
CROP = (440, 320)
check = Checks("cli_live_track")


def run(*args, timeout=300):
    return run_tool([KG], *args, timeout=timeout)


def boxes(record):
    return [d for d in record["detections"] if d["model"] == "box"]


def summary_counts(stderr):
    """(tracked, detected) from live's closing line."""
    m = re.search(r"; (\d+) tracked(?: \(mean [0-9.]+ ms\))?, (\d+) detected", stderr)
    return (int(m.group(1)), int(m.group(2))) if m else None


work = tempfile.mkdtemp(prefix="kg-live-track-")
try:
    scene = os.path.join(work, "box_in_scene.pgm")
    subprocess.run([TO_PGM, os.path.join(DATA, "box_in_scene.png"), scene], check=True)
    width, height, pixels = read_pgm(scene)
    frames = os.path.join(work, "frames")
    os.mkdir(frames)
    # Written last frame first; "pan_09" sorts before "pan_10" by name only.
    for i in reversed(range(FRAMES)):
        write_pgm_crop(os.path.join(frames, "pan_%02d.pgm" % i), pixels, width, 10 + STEP[0] * i,
                       10 + STEP[1] * i, *CROP)
    paths = [os.path.join(frames, "pan_%02d.pgm" % i) for i in range(FRAMES)]
    index = os.path.join(work, "box.kgi")
    build = run("build", "-q", "--no-look-alikes", os.path.join(DATA, "box.png"), "-o", index)
    if build.returncode != 0:
        sys.exit("cli_live_track: keygraph build failed: " + build.stderr)

    # 1. Tracking (the default).
    live = run("live", "--index", index, "--images", frames, "--json")
    check(live.returncode == 0, "live exits 0 (got %d: %s)" % (live.returncode, live.stderr))
    lines = json_lines(live.stdout)
    check([r["scene"] for r in lines] == paths, "frames in name order: %s"
          % [os.path.basename(r["scene"]) for r in lines])
    found = [boxes(r) for r in lines]
    check(all(len(b) == 1 for b in found), "the box on every frame once: %s"
          % [len(b) for b in found])
    ids = {b[0]["track"] for b in found if b}
    check(len(ids) == 1 and min(ids) >= 0, "one track id throughout: %s" % ids)
    check(lines[0]["detected"] and found[0] and not found[0][0]["tracked"],
          "the first frame is detected on")
    tracked = [r for r in lines if not r["detected"]]
    check(len(tracked) >= FRAMES // 2, "most frames tracked, not detected: %d of %d"
          % (len(tracked), FRAMES))
    check(all(all(d["tracked"] for d in r["detections"]) for r in tracked),
          "every object of a tracked frame was confirmed around its prediction")
    check(all(all(v == 0 for k, v in r["stats"].items() if isinstance(v, int)) and
              r["stats"]["truncated"] == [] for r in tracked),
          "a frame without detection has zero detection stats")
    check(all(r["time_ms"] > 0 for r in lines), "every frame has its time_ms")
    check(summary_counts(live.stderr) == (len(tracked), FRAMES - len(tracked)),
          "summary counts the tracked and the detected frames: %s" % live.stderr.splitlines()[-1:])
    check(re.search(r"\d+ tracked \(mean [0-9.]+ ms\), \d+ detected \(mean [0-9.]+ ms\)",
                    live.stderr) is not None, "summary gives the mean ms of each")

    # 2. Detection alone (--no-track): the same box, no frame tracked.
    alone = run("live", "--index", index, "--images", frames, "--json", "--no-track")
    check(alone.returncode == 0, "--no-track exits 0: " + alone.stderr)
    reference = json_lines(alone.stdout)
    check([r["scene"] for r in reference] == paths, "--no-track: frames in name order")
    check(all(r["detected"] for r in reference), "--no-track: every frame detected on")
    check(all(d["track"] == -1 and not d["tracked"] for r in reference for d in r["detections"]),
          "--no-track: no track ids")
    check([[d["model"] for d in r["detections"]] for r in reference] ==
          [[d["model"] for d in r["detections"]] for r in lines],
          "--no-track finds the same objects on every frame")
    check(summary_counts(alone.stderr) == (0, FRAMES), "--no-track summary: 0 tracked, %d detected"
          % FRAMES)
    # Tracked corners where detection puts them, and moving with the pan.
    worst = 0.0
    for mine, ref in zip(found, (boxes(r) for r in reference)):
        if mine and ref:
            for a, b in zip(mine[0]["corners"], ref[0]["corners"]):
                worst = max(worst, abs(a[0] - b[0]), abs(a[1] - b[1]))
    check(worst < 4.0, "tracked corners within 4 px of detection's (worst %.2f px)" % worst)
    if found[0] and found[-1]:
        first, last = found[0][0]["corners"][0], found[-1][0]["corners"][0]
        moved = (first[0] - last[0], first[1] - last[1])
        expected = (STEP[0] * (FRAMES - 1), STEP[1] * (FRAMES - 1))
        check(abs(moved[0] - expected[0]) < 3 and abs(moved[1] - expected[1]) < 3,
              "the box moved %s px over the pan, expected %s" % (moved, expected))

    # 3. Text output: each detection's track, tracked frames marked.
    text = run("live", "--index", index, "--images", frames, "--frames", "3")
    out = text.stdout.splitlines()
    check(text.returncode == 0 and len([l for l in out if "track " in l]) == 3,
          "text: a track on each detection line: %s" % out)
    check(any(l.endswith(", tracked") for l in out) and any("(tracked)" in l for l in out),
          "text: a tracked frame and its confirmed detection marked: %s" % out)

    # 4. An index without model appearances: said once, every frame detected.
    flat = os.path.join(work, "flat.kgi")
    res = run("build", "-q", "--no-look-alikes", "--set", "views.appearance_size=0",
              os.path.join(DATA, "box.png"), "-o", flat)
    check(res.returncode == 0, "build without appearances: " + res.stderr)
    res = run("live", "--index", flat, "--images", frames, "--json")
    said = [l for l in res.stderr.splitlines() if "no model appearances" in l]
    check(res.returncode == 0, "no appearances: exit 0 (got %d: %s)" % (res.returncode, res.stderr))
    check(len(said) == 1 and "every frame is detected" in said[0],
          "no appearances: said once on stderr: %s" % said)
    check(summary_counts(res.stderr) == (0, FRAMES), "no appearances: no frame tracked")
    check(all(len(boxes(r)) == 1 for r in json_lines(res.stdout)),
          "no appearances: the box still found on every frame")
finally:
    shutil.rmtree(work, ignore_errors=True)

check.finish()
