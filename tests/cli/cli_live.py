#!/usr/bin/env python3
"""keygraph live and bench end to end on image files, no camera needed.

A directory of frames made from opencv-doc images (box_in_scene as PNG and as
PGM, the box model itself as PGM, fruits.jpg without the box) goes through
`keygraph live --images` (platform/files -> the core detector -> JSON lines).
Checked: one JSON line per frame in file order, the keys and the detections
of `keygraph detect --json` on the same files (live --no-track; live's
additions, "detected", "track" and "tracked", aside), the box found
where detect finds it, nothing found in fruits.jpg, PNG and PGM of the same
picture giving the same result, --frames, --draw (PGM pictures, outlines
only where something was found), text output, SIGINT and SIGTERM on a
looping source (clean exit 0, only whole lines), bad frames, and one-line
errors for bad command lines. Then `keygraph bench` on two frames.

usage: cli_live.py KEYGRAPH KG_TO_PGM OPENCV_DATA_DIR
"""
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import time

from cli_support import Checks, json_lines, read_pgm, run_tool

KG, TO_PGM, DATA = (os.path.abspath(a) for a in sys.argv[1:4])
DETECT_KEYS = ["scene", "width", "height", "time_ms", "detections", "stats"]
LIVE_KEYS = ["scene", "width", "height", "time_ms", "detected", "detections", "stats"]
check = Checks("cli_live")


def run(*args, timeout=120):
    return run_tool([KG], *args, timeout=timeout)


def without_time(record):
    """The record without its time, its name and live's additions."""
    out = {k: v for k, v in record.items() if k not in ("time_ms", "scene", "detected")}
    out["detections"] = [{k: v for k, v in d.items() if k not in ("track", "tracked")}
                         for d in record.get("detections", [])]
    return out


work = tempfile.mkdtemp(prefix="kg-live-")
try:
    frames = os.path.join(work, "frames")
    os.mkdir(frames)
    index = os.path.join(work, "box.kgi")
    build = run("build", os.path.join(DATA, "box.png"), "-o", index)
    if build.returncode != 0:
        sys.exit("cli_live: keygraph build failed: " + build.stderr)
    shutil.copy(os.path.join(DATA, "box_in_scene.png"), os.path.join(frames, "0_scene.png"))
    for src, name in (("box_in_scene.png", "1_scene.pgm"), ("box.png", "2_box.pgm")):
        subprocess.run([TO_PGM, os.path.join(DATA, src), os.path.join(frames, name)], check=True)
    shutil.copy(os.path.join(DATA, "fruits.jpg"), os.path.join(frames, "3_fruits.jpg"))
    names = sorted(os.listdir(frames))
    paths = [os.path.join(frames, n) for n in names]

    # 1. JSON lines, compared with detect on the same files (detection on
    # every frame: tracking would follow the box from 0_scene.png into
    # 1_scene.pgm instead; tests/cli/cli_live_track.py tests it).
    live = run("live", "--index", index, "--images", frames, "--json", "--no-track")
    check(live.returncode == 0, "live --images exits 0 (got %d: %s)" % (live.returncode, live.stderr))
    lines = json_lines(live.stdout)
    detect = run("detect", "--index", index, "--json", *paths)
    check(detect.returncode == 0, "detect exits 0")
    reference = json_lines(detect.stdout)
    check(len(lines) == len(paths), "one line per frame (%d lines, %d frames)" % (len(lines), len(paths)))
    for record, ref, path in zip(lines, reference, paths):
        check(list(record) == LIVE_KEYS, "%s: keys %s" % (path, list(record)))
        check(list(ref) == DETECT_KEYS, "detect %s: keys %s" % (path, list(ref)))
        check(record["detected"] is True and
              all(d["track"] == -1 and d["tracked"] is False for d in record["detections"]),
              "%s: --no-track: detected, no track" % path)
        check(record["scene"] == path, "scene %s is the file %s" % (record["scene"], path))
        check(without_time(record) == without_time(ref), "%s: same result as detect" % path)
        check(record["time_ms"] > 0, "%s: time_ms > 0" % path)
    by_name = dict(zip(names, lines))
    for name in ("0_scene.png", "1_scene.pgm", "2_box.pgm"):
        found = [d["model"] for d in by_name.get(name, {}).get("detections", [])]
        check(found == ["box"], "%s: the box is found once (got %s)" % (name, found))
    check(by_name["3_fruits.jpg"]["detections"] == [], "fruits.jpg: nothing found")
    check(without_time(by_name["0_scene.png"]) == without_time(by_name["1_scene.pgm"]),
          "PNG and PGM of box_in_scene give the same result")
    corners = by_name["0_scene.png"]["detections"][0]["corners"]
    # The box's outline in box_in_scene (cf. tests/core/test_detection.cpp).
    check(100 < corners[0][0] < 135 and 145 < corners[0][1] < 180,
          "box top-left corner near (117, 161): %s" % corners[0])
    check("live: files " in live.stderr and "live: 4 frames in" in live.stderr and
          "; 0 tracked, 4 detected (mean " in live.stderr,
          "stderr names the source and gives the summary: " + live.stderr)

    # 2. --frames, text output.
    text = run("live", "--index", index, "--images", frames, "--frames", "2")
    out = text.stdout.splitlines()
    check(text.returncode == 0, "--frames 2 exits 0")
    heads = [l for l in out if not l.startswith("  ")]
    check(len(heads) == 2 and heads[0].startswith(paths[0] + ": 1 detection(s) in "),
          "--frames 2: two frames in text form: %s" % heads)
    check("stopped by --frames 2" in text.stderr, "--frames 2 named as the reason to stop")

    # 3. --draw: one PGM per frame; outlines only where something was found.
    draw = os.path.join(work, "draw")
    os.mkdir(draw)
    drawn = run("live", "--index", index, "--images", frames, "--draw", draw, "--json")
    check(drawn.returncode == 0, "--draw exits 0")
    check(sorted(os.listdir(draw)) == [os.path.splitext(n)[0] + ".pgm" for n in names],
          "--draw writes one PGM per frame: %s" % sorted(os.listdir(draw)))
    w, h, scene_pixels = read_pgm(os.path.join(frames, "1_scene.pgm"))
    dw, dh, drawn_pixels = read_pgm(os.path.join(draw, "1_scene.pgm"))
    changed = sum(a != b for a, b in zip(scene_pixels, drawn_pixels))
    check((dw, dh) == (w, h) and 500 < changed < 20000,
          "outline drawn on box_in_scene: %dx%d, %d pixels changed" % (dw, dh, changed))
    fw, fh, _ = read_pgm(os.path.join(draw, "3_fruits.pgm"))
    check((fw, fh) == (by_name["3_fruits.jpg"]["width"], by_name["3_fruits.jpg"]["height"]),
          "fruits picture has the frame's size")

    # 4. SIGINT / SIGTERM on a source that never ends (--loop): the frame in
    # progress is finished, the source stopped, exit 0, whole lines only.
    for sig in (signal.SIGINT, signal.SIGTERM):
        proc = subprocess.Popen([KG, "live", "--index", index, "--images", frames, "--loop",
                                 "--json"], stdout=subprocess.PIPE, stderr=subprocess.PIPE)
        seen = []
        deadline = time.time() + 60
        while len(seen) < 6 and time.time() < deadline:
            line = proc.stdout.readline()
            if not line:
                break
            seen.append(line)
        proc.send_signal(sig)
        try:
            rest, err = proc.communicate(timeout=30)
        except subprocess.TimeoutExpired:
            proc.kill()
            rest, err = proc.communicate()
            check(False, "live stops within 30 s of %s" % sig.name)
        output = b"".join(seen) + rest
        records = json_lines(output.decode())
        check(proc.returncode == 0, "%s: exit 0 (got %s)" % (sig.name, proc.returncode))
        check(len(records) >= 6 and output.endswith(b"\n"),
              "%s: %d whole JSON lines before stopping" % (sig.name, len(records)))
        check([r["scene"] for r in records[:8]] == (paths * 2)[:min(8, len(records))],
              "%s: --loop starts over after the last file" % sig.name)
        check(("stopped by " + sig.name) in err.decode(), "%s: summary says why it stopped" % sig.name)

    # 5. A bad file: one warning, the other frames still done, exit 1.
    bad = os.path.join(work, "bad")
    shutil.copytree(frames, bad)
    with open(os.path.join(bad, "1b_broken.pgm"), "wb") as f:
        f.write(b"P5\n10 10\n255\nshort")
    res = run("live", "--index", index, "--images", bad, "--json")
    warnings = [l for l in res.stderr.splitlines() if l.startswith("keygraph: ")]
    check(res.returncode == 1 and len(json_lines(res.stdout)) == 4,
          "bad frame: exit 1, the 4 good frames done (rc %d)" % res.returncode)
    check(len(warnings) == 1 and "1b_broken.pgm" in warnings[0] and "frame skipped" in warnings[0],
          "bad frame: one warning naming it: %s" % warnings)

    # 6. Bad command lines and inputs: one line on stderr, exit non-zero,
    # nothing on stdout.
    mser = os.path.join(work, "mser.kgi")
    run("build", "--detector", "mser", "--roi", "100,60,96,96", os.path.join(DATA, "box.png"),
        "-o", mser)
    missing = os.path.join(work, "missing")
    for args, needle in [
        ([], "no index given"),
        (["--index", index], "no frame source given"),
        (["--index", os.path.join(work, "none.kgi"), "--images", frames], "none.kgi"),
        (["--index", index, "--images", missing], "missing: no such file or directory"),
        (["--index", index, "--images", frames, "--v4l2", "/dev/video0"], "give one source"),
        (["--index", index, "--v4l2", os.path.join(work, "video-missing")], "no such device"),
        (["--index", index, "--v4l2", "/dev/null"], "not a V4L2 device"),
        (["--index", index, "--images", frames, "--frames", "0"], "--frames 0"),
        (["--index", index, "--images", frames, "--frames"], "--frames needs a value"),
        (["--index", index, "--v4l2", "/dev/video0", "--size", "640"], "WIDTHxHEIGHT"),
        (["--index", index, "--v4l2", "/dev/video0", "--loop"], "--loop applies to --images"),
        (["--index", index, "--images", frames, "--size", "64x48"], "--size applies to cameras"),
        (["--index", index, "--images", frames, "--draw", missing], "no such directory"),
        (["--index", index, "--images", frames, "--draw", frames], "is the --images directory"),
        (["--index", index, "--images", frames, "--bogus"], "unknown option --bogus"),
        (["--index", mser, "--images", frames], "--detector mser"),
    ]:
        res = run("live", *args)
        err = res.stderr.splitlines()
        check(res.returncode != 0 and len(err) == 1 and needle in err[0] and not res.stdout,
              "live %s: one error line with '%s' (rc %d, stderr %s)"
              % (" ".join(args), needle, res.returncode, err))

    # 7. bench: every stage, ordered summaries, the detections of detect.
    res = run("bench", "--index", index, "--repeat", "3", "--json", paths[1], paths[2])
    check(res.returncode == 0, "bench exits 0: " + res.stderr)
    rows = json_lines(res.stdout)
    check([r["frame"] for r in rows] == paths[1:3], "bench: one line per frame, in order")
    stages = ["keypoints", "graph", "describe", "select", "pose", "total", "other"]
    for r in rows:
        check(r["repeat"] == 3 and list(r["ms"]) == stages, "bench %s: 3 runs, every stage" % r["frame"])
        check(r["detections"] == {"min": 1, "max": 1}, "bench %s: the box in every run" % r["frame"])
        for stage, s in r["ms"].items():
            check(0 <= s["min"] <= s["median"] <= s["p90"] <= s["max"] or stage == "other",
                  "bench %s %s: min <= median <= p90 <= max: %s" % (r["frame"], stage, s))
        check(r["ms"]["total"]["min"] >= r["ms"]["keypoints"]["min"], "total includes keypoints")
    res = run("bench", "--index", index, "--repeat", "2", paths[2])
    check(res.returncode == 0 and "  total " in res.stdout and "detector workspace:" in res.stdout,
          "bench text output has the total and the workspace: " + res.stdout)
    for args, needle in [
        (["--index", index], "no frames given"),
        (["--index", index, "--repeat", "0", paths[2]], "--repeat 0"),
        (["--index", index, os.path.join(bad, "1b_broken.pgm")], "1b_broken.pgm"),
        (["--index", mser, paths[2]], "--detector mser"),
    ]:
        res = run("bench", *args)
        err = res.stderr.splitlines()
        check(res.returncode != 0 and len(err) == 1 and needle in err[0],
              "bench %s: one error line with '%s' (stderr %s)" % (" ".join(args), needle, err))
finally:
    shutil.rmtree(work, ignore_errors=True)

check.finish()
