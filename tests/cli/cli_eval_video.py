#!/usr/bin/env python3
"""keygraph synth --video and keygraph eval --video end to end (issue 36).

- A generated sequence (seed 2, 300 frames, 3 signs as models):
  written with its manifest (every frame in order; frames with the sign,
  without it, and not scored), then evaluated with tracking and detection
  alone in one run, the scores asserted: tracking finds the sign in most
  frames and at least as often as detection alone, within 5 px in most,
  tracks most frames, one track id without a switch, lets go of the sign
  within 2 frames when it leaves or is covered, and makes no more wrong
  detections than detection alone.
- The real sequence ($KG_DATA_DIR/real/video/poster-rotation, when given):
  its manifest made by pot_video_manifest.py, the model photographed in
  another video: every annotated frame found within 15 px with one id.
- Bad input to the new options: one clear line, a non-zero exit, nothing
  written.

usage: cli_eval_video.py KEYGRAPH OPENCV_DATA_DIR [KG_DATA_DIR] [sanitized]
  sanitized (a sanitizer build, where evaluating the 300 frames takes
  minutes): the JSON run scores 56 frames of the sequence (frames 185-240:
  the end of the occlusion and the sign leaving the frame and coming back)
  instead of all 300, with the checks that hold for any stretch of it (the
  counts, the parts, one id, the sign let go within 2 frames, tracking
  finding it more often than detection alone, no more wrong detections);
  the proportions measured over the whole sequence (tracking finds the sign
  in 82 % of its frames, the blurred pans) are checked in the ci suite.
  The table, the same scores as the JSON as text, is printed for 24 frames
  (around the end of the approach and the start of the pans: two more
  parts) instead of all 300 again. The real poster video and the bad input
  run as in the ci suite.
"""
import json
import os
import subprocess
import sys
import tempfile

SANITIZED = sys.argv[-1] == "sanitized" and len(sys.argv) > 3
ARGS = sys.argv[1:-1] if SANITIZED else sys.argv[1:]
KG, OPENCV = (os.path.abspath(a) for a in ARGS[0:2])
DATA = os.environ.get("KG_DATA_DIR") or (ARGS[2] if len(ARGS) > 2 else "")
HERE = os.path.dirname(os.path.abspath(__file__))
failures = []


def check(ok, what):
    if not ok:
        failures.append(what)
        print("FAIL: " + what, file=sys.stderr)


def run(*args):
    return subprocess.run([KG, *args], capture_output=True, text=True)


def refused(args, needle, what):
    r = run(*args)
    lines = r.stderr.strip().splitlines()
    check(r.returncode != 0, what + ": exit code " + str(r.returncode))
    check(len(lines) == 1 and lines[0].startswith("keygraph: ") and needle in lines[0],
          what + ": stderr " + repr(r.stderr))


def modes(scores):
    return {m["mode"]: m for m in scores["modes"]}


def excerpt(manifest, out, first, last):
    """Frames first..last of a video manifest, with the comment lines (the
    header and the parts) that come before the last."""
    lines, frame = [], 0
    with open(manifest) as f:
        for line in f:
            if line.startswith("#"):
                if frame <= last:
                    lines.append(line)
                continue
            if first <= frame <= last:
                lines.append(line)
            frame += 1
    with open(out, "w") as f:
        f.writelines(lines)


with tempfile.TemporaryDirectory(prefix="kg_eval_video.") as work:
    seq = os.path.join(work, "seq")
    r = run("synth", "--video", "-o", seq, "--seed", "2", "--frames", "300", "--signs", "3",
            "--backgrounds", OPENCV, "-q")
    check(r.returncode == 0, "synth --video: " + r.stderr)
    lines = [l for l in open(os.path.join(seq, "video.jsonl")) if not l.startswith("#")]
    check(len(lines) == 300, "one manifest line per frame: %d" % len(lines))
    frames = [json.loads(l) for l in lines]
    check([f["scene"] for f in frames] == ["frames/%04d.jpg" % i for i in range(300)],
          "frames in order")
    with_sign = sum(1 for f in frames if f.get("instances"))
    without = sum(1 for f in frames if "instances" in f and not f["instances"])
    check(with_sign >= 200, "frames with the sign: %d" % with_sign)
    check(without >= 5, "frames without it (left the frame, covered): %d" % without)
    check(len(os.listdir(os.path.join(seq, "signs"))) == 3, "3 models")

    # The JSON run: the whole sequence, or under the sanitizers an excerpt
    # with the sign leaving the frame and coming back.
    json_manifest, json_frames, json_with = os.path.join(seq, "video.jsonl"), frames, with_sign
    if SANITIZED:
        json_manifest = os.path.join(seq, "leave.jsonl")
        excerpt(os.path.join(seq, "video.jsonl"), json_manifest, 185, 240)
        json_frames = frames[185:241]
        json_with = sum(1 for f in json_frames if f.get("instances"))
        check(sum(1 for f in json_frames if "instances" in f and not f["instances"]) >= 5,
              "the excerpt has frames without the sign")
    n = len(json_frames)
    r = run("eval", "--video", json_manifest, "--models", os.path.join(seq, "signs"), "--json",
            "-q")
    check(r.returncode == 0, "eval --video: " + r.stderr)
    if r.returncode == 0:
        s = json.loads(r.stdout)
        m = modes(s)
        t, d = m["tracking"], m["detection alone"]
        print("tracking:", t, "\ndetection alone:", d)
        check(s["frames"] == n and s["with_object"] == json_with, "counts " + r.stdout)
        check(t["instances"] == json_with and d["instances"] == json_with, "instances scored")
        tp = {p["part"]: p for p in t["parts"]}
        dp = {p["part"]: p for p in d["parts"]}
        if not SANITIZED:
            # (measured when written: 228 and 195 of 257, 228 within 5 px, 198
            # frames tracked and 102 detected, the pans 53 and 34 of 60)
            check(t["found"] >= 0.82 * with_sign, "tracking finds the sign: %d" % t["found"])
            check(t["found"] >= d["found"] + 0.06 * with_sign,
                  "tracking finds it clearly more often than detection alone: %d, %d"
                  % (t["found"], d["found"]))
            check(t["found_fine"] >= 0.8 * with_sign, "within 5 px: %d" % t["found_fine"])
            check(t["frames_tracked"] >= 1.5 * t["frames_detected"], "mostly tracked frames")
            check(sorted(tp) == ["approach", "leave", "occlusion", "pans", "turns"], "the parts")
            if "pans" in tp and "pans" in dp:
                check(tp["pans"]["found"] >= dp["pans"]["found"] + 10,
                      "the blurred pans: %d, %d" % (tp["pans"]["found"], dp["pans"]["found"]))
        else:
            # (measured when written: 22 and 18 of 24 in the sanitize build,
            # 23 and 16 of 25 in the ci build, whose generated frames differ a
            # little; 20 frames tracked and 36 detected in both; the sign
            # leaving: 9 and 5 of 11, 10 and 3 of 12)
            check(t["found"] >= 0.8 * json_with, "tracking finds the sign: %d" % t["found"])
            check(t["found"] >= d["found"] + 2,
                  "tracking finds it more often than detection alone: %d, %d"
                  % (t["found"], d["found"]))
            check(t["found_fine"] >= 0.8 * json_with, "within 5 px: %d" % t["found_fine"])
            check(t["frames_tracked"] >= 10, "tracked frames: %d" % t["frames_tracked"])
            check(sorted(tp) == ["leave", "occlusion"], "the parts of the excerpt")
            if "leave" in tp and "leave" in dp:
                check(tp["leave"]["found"] >= dp["leave"]["found"] + 2,
                      "the sign leaving: %d, %d" % (tp["leave"]["found"], dp["leave"]["found"]))
        check(d["frames_tracked"] == 0 and d["frames_detected"] == n, "detection alone")
        check(t["id_switches"] == 0, "no id switch")
        check(t["drop_events"] >= 1 and t["drop_frames_max"] <= 2,
              "lets go within 2 frames: %d" % t["drop_frames_max"])
        check(t["wrong"] <= d["wrong"], "no more wrong detections than detection alone")
        check(0 <= t["jitter_rms"] < 1.0, "jitter: %s" % t["jitter_rms"])
    table_manifest = os.path.join(seq, "video.jsonl")
    if SANITIZED:
        table_manifest = os.path.join(seq, "excerpt.jsonl")
        excerpt(os.path.join(seq, "video.jsonl"), table_manifest, 70, 93)
    r = run("eval", "--video", table_manifest, "--models", os.path.join(seq, "signs"), "-q")
    check(r.returncode == 0 and "tracking" in r.stdout and "id switches" in r.stdout,
          "the table: " + r.stdout)
    if SANITIZED:
        check("24 frames" in r.stdout and "  approach, " in r.stdout and "  pans, " in r.stdout,
              "the table of the excerpt: 24 frames, two parts: " + r.stdout)

    # The real sequence.
    poster = os.path.join(DATA, "real", "video", "poster-rotation") if DATA else ""
    if not poster:
        print("the real poster video not run: no KG_DATA_DIR (tests/CMakeLists.txt passes it "
              "when $KG_DATA_DIR/real exists)")
    if poster:
        check(os.path.isdir(poster), "no directory " + poster)
    if poster and os.path.isdir(poster):
        idx = os.path.join(work, "poster.kgi")
        r = run("build", "-q", "--name", "poster", os.path.join(poster, "model-other-video.png"),
                "-o", idx)
        check(r.returncode == 0, "build poster: " + r.stderr)
        manifest = os.path.join(work, "poster.jsonl")
        subprocess.run([sys.executable, os.path.join(HERE, "pot_video_manifest.py"), poster,
                        os.path.join(poster, "corners_other_model.txt"), "poster", manifest],
                       check=True)
        r = run("eval", "--video", manifest, "--index", idx, "--json", "-q")
        check(r.returncode == 0, "eval --video poster: " + r.stderr)
        if r.returncode == 0:
            s = json.loads(r.stdout)
            t, d = modes(s)["tracking"], modes(s)["detection alone"]
            print("poster tracking:", t, "\nposter detection alone:", d)
            check(s["frames"] == 50 and s["with_object"] == 26 and s["tolerance"] == 15,
                  "poster counts")
            check(t["found"] == 26, "poster: every annotated frame within 15 px: %d" % t["found"])
            check(t["found_fine"] >= 20, "poster: within 5 px: %d" % t["found_fine"])
            check(t["track_ids"] == 1 and t["id_switches"] == 0, "poster: one id")
            check(t["frames_tracked"] >= 30, "poster: tracked frames %d" % t["frames_tracked"])

    # Bad input.
    refused(["synth", "--video", "-o", os.path.join(work, "a"), "--frames", "10"], "30",
            "too few frames")
    refused(["synth", "--video", "-o", os.path.join(work, "b"), "--size", "100x100"], "--size",
            "a small size")
    refused(["synth", "--video", "-o", os.path.join(work, "c"), "--size", "640"], "--size",
            "a size without x")
    refused(["synth", "--video", "-o", os.path.join(work, "d"), "--sign-free", "0.5"],
            "--sign-free", "--sign-free with --video")
    refused(["synth", "-o", os.path.join(work, "e"), "--size", "1280x720"], "--size",
            "--size on stills without --range")
    for name in "abcde":
        check(not os.path.exists(os.path.join(work, name)), "nothing written for " + name)
    refused(["synth", "--video", "-o", seq], "not empty", "an existing directory")
    refused(["eval", "--video"], "--video", "no manifest")
    refused(["eval", "--video", os.path.join(work, "none.jsonl"), "--models",
             os.path.join(seq, "signs"), "-q"], "none.jsonl", "a missing manifest")
    refused(["eval", "--video", os.path.join(seq, "video.jsonl")], "--models", "no models")
    refused(["eval", "--video", os.path.join(seq, "video.jsonl"), "--models",
             os.path.join(seq, "signs"), "--index", os.path.join(work, "x.kgi")], "one of",
            "--models and --index")
    refused(["eval", "--video", os.path.join(seq, "video.jsonl"), "--models",
             os.path.join(seq, "signs"), "--detect-interval", "0"], "--detect-interval",
            "--detect-interval 0")
    bad = os.path.join(work, "bad.jsonl")
    for text, needle, what in [
        ('{"scene": "seq/frames/0000.jpg", "extra": 1}\n', ":1:", "a frame line with another key"),
        ('{"scene": "seq/frames/0000.jpg"}\n{"scene": "seq/frames/9999.jpg"}\n', ":2:",
         "a missing frame"),
        ('{"scene": "seq/frames/0000.jpg", "instances": [{"model": "nobody", '
         '"corners": [[0,0],[9,0],[9,9],[0,9]]}]}\n', "nobody", "an unknown model"),
        ('{"scene": "seq/signs"}\n', "directory", "a directory as a frame"),
        ("# nothing\n", "no scenes", "no frames"),
    ]:
        with open(bad, "w") as f:
            f.write(text)
        refused(["eval", "--video", bad, "--models", os.path.join(seq, "signs"), "-q"], needle,
                what)
    # Frames of two sizes.
    sign = sorted(os.listdir(os.path.join(seq, "signs")))[0]
    with open(bad, "w") as f:
        f.write('{"scene": "seq/frames/0000.jpg"}\n{"scene": "seq/signs/%s"}\n' % sign)
    refused(["eval", "--video", bad, "--models", os.path.join(seq, "signs"), "-q"],
            "one frame size",
            "frames of two sizes")

if failures:
    print("%d check(s) failed" % len(failures), file=sys.stderr)
    sys.exit(1)
print("ok")
