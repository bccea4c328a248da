#!/usr/bin/env python3
"""Soak test of keygraph live (issue 36, item 4): a long run over looping image
files with the index file replaced underneath it, as a device does when new
signs are deployed.

`keygraph live --index WORK/models.kgi --images FRAMES --loop --json --frames N`
runs while this script, every N / RELOADS frames, writes the same index
content to a new file and renames it over WORK/models.kgi (a new inode: live
sees the change and reloads). Checked:
- live exits 0 with N JSON lines, no error on stderr, and reloads the index
  RELOADS times (its "reloaded" lines);
- resident memory (VmRSS) and open file descriptors of the live process,
  sampled at every replacement: the descriptors not growing (none of the
  later half above the first sample; a reload in progress may hold one
  more for a moment), the memory after
  the first reload within RSS_SLACK_KB of its highest value by then (it
  must not grow with frames or reloads);
- detections identical before and after each reload: on every frame where
  detection ran, the same objects with the same corners for the same image
  (bit for bit); on tracked frames the same objects, corners within 1 px of
  the image's detection.

usage: soak_live.py KEYGRAPH INDEX.kgi FRAMES_DIR FRAMES RELOADS
       soak_live.py KEYGRAPH --opencv-doc KG_TO_PGM DATA_DIR FRAMES RELOADS
  The second form makes its inputs from opencv-doc: an index of box.png and
  the frames box_in_scene, box_in_scene again (a frame to track) and box.
  The short version is a ctest (cli_live_soak, tests/cli/CMakeLists.txt);
  the long one (100 000 frames, 100 reloads; minutes on a release build):
    tests/cli/soak_live.py build/release/src/cli/keygraph --opencv-doc \
      build/release/tests/kg_to_pgm /usr/share/doc/opencv-doc/examples/data 100000 100
"""
import json
import os
import shutil
import subprocess
import sys
import tempfile
import threading

RSS_SLACK_KB = 4096


def fail(message):
    print("soak_live: FAIL: " + message, file=sys.stderr)
    return 1


def status_kb(pid, field):
    with open(f"/proc/{pid}/status") as f:
        for line in f:
            if line.startswith(field + ":"):
                return int(line.split()[1])
    return -1


def open_fds(pid):
    return len(os.listdir(f"/proc/{pid}/fd"))


def make_inputs(kg, to_pgm, data, work):
    """(index, frames directory) made from opencv-doc's box images."""
    index = os.path.join(work, "box.kgi")
    frames = os.path.join(work, "frames")
    os.mkdir(frames)
    subprocess.run([kg, "build", "-q", os.path.join(data, "box.png"), "-o", index], check=True,
                   stdout=subprocess.DEVNULL)
    for name, image in (("a", "box_in_scene"), ("b", "box_in_scene"), ("c", "box")):
        subprocess.run([to_pgm, os.path.join(data, image + ".png"),
                        os.path.join(frames, f"{name}_{image}.pgm")], check=True)
    return index, frames


def main(argv):
    if len(argv) == 7 and argv[2] == "--opencv-doc":
        kg, to_pgm, data = (os.path.abspath(a) for a in (argv[1], argv[3], argv[4]))
        index = frames_dir = None
        counts = argv[5:7]
    elif len(argv) == 6:
        kg, index, frames_dir = (os.path.abspath(a) for a in argv[1:4])
        counts = argv[4:6]
    else:
        print(__doc__, file=sys.stderr)
        return 2
    total, reloads = int(counts[0]), int(counts[1])
    if total < 2 * (reloads + 1):
        return fail("give at least two frames per reload")
    work = tempfile.mkdtemp(prefix="kg-soak.")
    try:
        if index is None:
            index, frames_dir = make_inputs(kg, to_pgm, data, work)
        live_index = os.path.join(work, "models.kgi")
        shutil.copyfile(index, live_index)
        proc = subprocess.Popen(
            [kg, "live", "--index", live_index, "--images", frames_dir, "--loop", "--json",
             "--frames", str(total)],
            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        stderr_lines = []
        reader = threading.Thread(target=lambda: stderr_lines.extend(proc.stderr), daemon=True)
        reader.start()

        lines = 0
        detected = {}  # image -> its detections on frames where detection ran
        tracked = []  # (image, detections) of tracked frames, checked at the end
        samples = []  # (frames, rss_kb, fds) at each replacement
        every = total // (reloads + 1)
        replaced = 0
        mismatches = []
        for line in proc.stdout:
            frame = json.loads(line)
            lines += 1
            image = os.path.basename(frame["scene"].split(":")[0])
            found = sorted((d["model"], tuple(map(tuple, d["corners"])))
                           for d in frame["detections"])
            if frame["detected"]:
                first = detected.setdefault(image, found)
                if first != found and len(mismatches) < 5:
                    mismatches.append(f"frame {lines}: {image}: {found} after {first}")
            else:
                tracked.append((image, found))
            if replaced < reloads and lines == every * (replaced + 1):
                samples.append((lines, status_kb(proc.pid, "VmRSS"), open_fds(proc.pid)))
                fresh = os.path.join(work, f"models.{replaced}.tmp")
                shutil.copyfile(index, fresh)
                os.replace(fresh, live_index)
                replaced += 1
        rc = proc.wait(timeout=600)
        reader.join(timeout=60)

        failures = 0
        if rc != 0:
            failures += fail(f"live exited {rc}: {''.join(stderr_lines[-5:])}")
        if lines != total:
            failures += fail(f"{lines} JSON lines for {total} frames")
        errors = [l for l in stderr_lines if l.startswith("keygraph:")]
        if errors:
            failures += fail(f"{len(errors)} error lines, the first: {errors[0].strip()}")
        reloaded = sum(1 for l in stderr_lines if " changed: reloaded" in l)
        if reloaded != reloads:
            failures += fail(f"{reloaded} reloads for {reloads} replacements")
        for m in mismatches:
            failures += fail("detections changed: " + m)
        for image, found in tracked:
            ref = detected.get(image)
            same = ref is not None and [m for m, _ in ref] == [m for m, _ in found] and all(
                abs(a - b) <= 1.0 for (_, ca), (_, cb) in zip(ref, found)
                for pa, pb in zip(ca, cb) for a, b in zip(pa, pb))
            if not same:
                failures += fail(f"tracked {image}: {found}, detected {ref}")
                break
        # A sample can catch a reload with the new file open for a moment
        # (one descriptor more, once); a leak stays, so every later sample
        # would be higher than the first.
        fd_counts = [s[2] for s in samples]
        if fd_counts and min(fd_counts[len(fd_counts) // 2:]) > fd_counts[0]:
            failures += fail(f"open descriptors grew: {samples}")
        fds = set(fd_counts)
        if len(samples) >= 3:
            settled = max(s[1] for s in samples[:2])
            grown = [s for s in samples[2:] if s[1] > settled + RSS_SLACK_KB]
            if grown:
                failures += fail(f"resident memory grew past {settled} KB + {RSS_SLACK_KB}: {grown[:3]}")
        rss = [s[1] for s in samples]
        print(f"soak_live: {lines} frames, {reloaded} reloads, {len(tracked)} tracked frames; "
              f"VmRSS {min(rss) if rss else -1}-{max(rss) if rss else -1} KB, "
              f"open descriptors {sorted(fds)}; {len(detected)} images, "
              f"detections the same after every reload: {'no' if mismatches else 'yes'}")
        return 1 if failures else 0
    finally:
        shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    sys.exit(main(sys.argv))
