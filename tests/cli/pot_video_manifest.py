#!/usr/bin/env python3
"""Writes the video manifest of `keygraph eval --video` (docs/EVAL.md) for a
sequence laid out as ../shared/data/real/video/poster-rotation: frames/*.jpg
in name order, and a corners file with one line per annotated frame,
`FRAME x1 y1 x2 y2 x3 y3 x4 y4` (POT's order, the model's corners (0,0),
(w,0), (w,h), (0,h)). Frames without a line are written without
"instances" (processed, not scored). Scene paths are absolute.

usage: pot_video_manifest.py SEQUENCE_DIR CORNERS_FILE MODEL_NAME OUT.jsonl
"""
import json
import os
import sys


def main():
    if len(sys.argv) != 5:
        sys.exit(__doc__)
    seq, corners_file, model, out = sys.argv[1:5]
    frames_dir = os.path.abspath(os.path.join(seq, "frames"))
    corners = {}
    with open(corners_file) as f:
        for line in f:
            parts = line.split()
            if len(parts) != 9:
                continue
            xy = [float(v) for v in parts[1:]]
            corners[parts[0]] = [[xy[2 * i], xy[2 * i + 1]] for i in range(4)]
    lines = []
    for name in sorted(os.listdir(frames_dir)):
        scene = {"scene": os.path.join(frames_dir, name)}
        if name in corners:
            scene["instances"] = [{"model": model, "corners": corners[name]}]
        lines.append(json.dumps(scene))
    with open(out, "w") as f:
        f.write("\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
