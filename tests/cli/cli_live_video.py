#!/usr/bin/env python3
"""keygraph live --video end to end on opencv-doc's vtest.avi (issue 36).

The video goes through `keygraph live --video` (platform/files/video_source
over OpenCV videoio -> the detector -> JSON lines). Checked: 20 JSON lines of
768x576 frames named FILE:N in order, the source described on stderr;
--draw writes the decoded gray frames; an index built from a crop of frame 0
(cut from the drawn PGM) is found in frame 0 where the crop was taken, with
the detections `keygraph detect` gives on that PGM; --loop starts the video
again after its last frame (Megamind.avi, shorter); and one error line,
nothing on stdout, exit != 0 for a file that is not a video, a missing file,
a directory, a FIFO, --video with --images and --video with --size.

With a third argument `without-video` (a build without OpenCV videoio):
only the one error line of --video.

usage: cli_live_video.py KEYGRAPH OPENCV_DATA_DIR [without-video | sanitized]
  sanitized: the --loop check (545 detections of Megamind.avi, over 300 s
  under AddressSanitizer) is left out, and says so
"""
import os
import shutil
import sys
import tempfile

from cli_support import Checks, json_lines, read_pgm, run_tool, write_pgm_crop

KG, DATA = (os.path.abspath(a) for a in sys.argv[1:3])
VIDEO = os.path.join(DATA, "vtest.avi")
check = Checks("cli_live_video")


def run(*args, timeout=240):
    return run_tool([KG], *args, timeout=timeout)


work = tempfile.mkdtemp(prefix="kg-live-video-")
try:
    box = os.path.join(work, "box.kgi")
    build = run("build", os.path.join(DATA, "box.png"), "-o", box)
    if build.returncode != 0:
        sys.exit("cli_live_video: keygraph build failed: " + build.stderr)
    if sys.argv[3:] == ["without-video"]:
        # A build without OpenCV videoio: --video is refused in one line.
        res = run("live", "--index", box, "--video", VIDEO)
        err = res.stderr.splitlines()
        check(res.returncode != 0 and len(err) == 1 and "built without video support" in err[0],
              "--video without videoio: rc %d, stderr %s" % (res.returncode, err))
        check.finish()

    # 1. 20 frames as JSON lines, in order, at the video's size.
    live = run("live", "--index", box, "--video", VIDEO, "--frames", "20", "--json")
    check(live.returncode == 0, "live --video exits 0 (got %d: %s)" % (live.returncode, live.stderr))
    lines = json_lines(live.stdout)
    check(len(lines) == 20, "20 JSON lines (got %d)" % len(lines))
    check([r["scene"] for r in lines] == ["%s:%d" % (VIDEO, i) for i in range(20)],
          "frames named FILE:0 .. FILE:19: %s" % [r["scene"] for r in lines[:3]])
    check(all((r["width"], r["height"]) == (768, 576) for r in lines), "768x576 frames")
    check(all(r["time_ms"] > 0 for r in lines), "time_ms > 0 on every frame")
    check(("live: video %s: 768x576" % VIDEO) in live.stderr and "stopped by --frames 20" in live.stderr,
          "stderr describes the video and why it stopped: " + live.stderr)

    # 2. --draw: the decoded gray frames (the box is not in vtest.avi, so
    # nothing is drawn over them).
    draw = os.path.join(work, "draw")
    os.mkdir(draw)
    drawn = run("live", "--index", box, "--video", VIDEO, "--frames", "2", "--json", "--draw", draw)
    check(drawn.returncode == 0, "--draw exits 0: " + drawn.stderr)
    check(sorted(os.listdir(draw)) == ["frame_000000.pgm", "frame_000001.pgm"],
          "--draw: frame_000000.pgm and frame_000001.pgm: %s" % sorted(os.listdir(draw)))
    check(all(r["detections"] == [] for r in json_lines(drawn.stdout)), "no box in vtest.avi")
    frame0 = os.path.join(draw, "frame_000000.pgm")
    width, height, pixels = read_pgm(frame0)
    check((width, height) == (768, 576), "drawn frame 768x576 (got %dx%d)" % (width, height))
    # Gray, not one colour channel: the frame has many gray levels.
    check(len(set(pixels)) > 100, "frame 0 has %d gray levels" % len(set(pixels)))

    # 3. A crop of frame 0 (the building's facade, top left) is found there.
    x0, y0, w, h = 40, 20, 260, 200
    crop = os.path.join(work, "facade.pgm")
    write_pgm_crop(crop, pixels, width, x0, y0, w, h)
    facade = os.path.join(work, "facade.kgi")
    build = run("build", crop, "-o", facade)
    check(build.returncode == 0, "build from the crop: " + build.stderr)
    found = run("live", "--index", facade, "--video", VIDEO, "--frames", "1", "--json", "--no-track")
    check(found.returncode == 0, "live with the crop's index exits 0: " + found.stderr)
    records = json_lines(found.stdout)
    detections = records[0]["detections"] if records else []
    check([d["model"] for d in detections] == ["facade"],
          "the crop is found once in frame 0: %s" % [d["model"] for d in detections])
    if detections:
        expected = [[x0, y0], [x0 + w, y0], [x0 + w, y0 + h], [x0, y0 + h]]
        error = max(abs(c[i] - e[i]) for c, e in zip(detections[0]["corners"], expected)
                    for i in (0, 1))
        check(error < 6, "corners within 6 px of the crop's: %s (max error %.1f)"
              % (detections[0]["corners"], error))
    detect = run("detect", "--index", facade, "--json", frame0)
    reference = json_lines(detect.stdout)
    check(detect.returncode == 0 and reference and records and
          [d["corners"] for d in reference[0]["detections"]] == [d["corners"] for d in detections],
          "live on the video's frame 0 finds what detect finds on its PGM")

    # 4. --loop: Megamind.avi (270 frames) played twice over.
    if sys.argv[3:] == ["sanitized"]:
        print("cli_live_video: the --loop check is not run in a sanitizer build (545 detections)")
    else:
        megamind = os.path.join(DATA, "Megamind.avi")
        once = run("live", "--index", box, "--video", megamind, "--json", "--no-track")
        count = len(json_lines(once.stdout))
        check(once.returncode == 0 and count > 10 and "stopped by end of the video" in once.stderr,
              "Megamind.avi played to its end: %d frames (%s)" % (count, once.stderr))
        looped = run("live", "--index", box, "--video", megamind, "--json", "--loop", "--no-track",
                     "--frames", str(count + 5))
        loop_lines = json_lines(looped.stdout)
        check(looped.returncode == 0 and len(loop_lines) == count + 5,
              "--loop: %d frames from a video of %d (rc %d: %s)"
              % (len(loop_lines), count, looped.returncode, looped.stderr))
        if len(loop_lines) == count + 5:
            check([r["scene"] for r in loop_lines[count - 1:count + 1]] ==
                  ["%s:%d" % (megamind, count - 1), "%s:%d" % (megamind, count)],
                  "--loop: frame numbers go on after the last frame")
            first = [(r["width"], r["height"], r["detections"]) for r in loop_lines[:5]]
            again = [(r["width"], r["height"], r["detections"]) for r in loop_lines[count:]]
            check(first == again, "--loop: the second pass starts with the first pass's frames")

    # 5. One error line, nothing on stdout, exit != 0.
    text = os.path.join(work, "notes.avi")
    with open(text, "w") as f:
        f.write("not a video, only text\n" * 100)
    fifo = os.path.join(work, "fifo.avi")
    os.mkfifo(fifo)
    for args, needle in [
        (["--video", text], "cannot open video %s (" % text),
        (["--video", os.path.join(work, "missing.avi")], "missing.avi: no such file"),
        (["--video", work], "is a directory"),
        (["--video", fifo], "is a FIFO"),
        (["--video", VIDEO, "--images", DATA], "give one source"),
        (["--images", DATA, "--video", VIDEO], "give one source"),
        (["--video", VIDEO, "--size", "640x480"], "--size applies to cameras only"),
        (["--video"], "--video needs a value"),
    ]:
        res = run("live", "--index", box, *args, timeout=60)
        err = res.stderr.splitlines()
        check(res.returncode != 0 and len(err) == 1 and err[0].startswith("keygraph: ") and
              needle in err[0] and not res.stdout,
              "live %s: one error line with '%s' (rc %d, stderr %s)"
              % (" ".join(args), needle, res.returncode, err))

    # 6. --help names the source.
    res = run("live", "--help")
    check(res.returncode == 0 and "--video FILE" in res.stdout, "live --help lists --video FILE")
finally:
    shutil.rmtree(work, ignore_errors=True)

check.finish()
