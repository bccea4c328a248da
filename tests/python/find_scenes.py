#!/usr/bin/env python3
"""The Python binding on real frames: finds an index's models in PGM frames
and prints what tests/capi/find.c prints (one line per detection), so that
compare_find.py holds it to the C++ API's corners. Each frame is handed
over as a view into a wider array (rows 40 bytes longer than the image, as
a camera's Y plane often is), which the binding reads in place.
  find_scenes.py INDEX FRAME.pgm...
"""
import os
import sys

import numpy as np

import keygraph


def read_pgm(path):
    """A binary PGM (P5, maxval 255) as a 2-D uint8 array."""
    with open(path, "rb") as f:
        data = f.read()
    fields, at = [], 2
    if data[:2] != b"P5":
        raise ValueError(f"{path}: not a P5 PGM")
    while len(fields) < 3:
        while data[at:at + 1].isspace() or data[at:at + 1] == b"#":
            if data[at:at + 1] == b"#":
                at = data.index(b"\n", at)
            at += 1
        start = at
        while data[at:at + 1].isdigit():
            at += 1
        fields.append(int(data[start:at]))
    width, height, maxval = fields
    if maxval != 255:
        raise ValueError(f"{path}: not 8-bit")
    at += 1  # one whitespace byte
    return np.frombuffer(data, dtype=np.uint8, count=width * height, offset=at).reshape(height, width)


def main(argv):
    if len(argv) < 2:
        sys.exit("usage: find_scenes.py INDEX FRAME.pgm...")
    frames = [read_pgm(p) for p in argv[1:]]
    index = keygraph.Index(argv[0])
    detector = keygraph.Detector(index, max_width=max(f.shape[1] for f in frames),
                                 max_height=max(f.shape[0] for f in frames))
    for path, frame in zip(argv[1:], frames):
        height, width = frame.shape
        wide = np.full((height, width + 40), 0xA5, dtype=np.uint8)
        wide[:, :width] = frame
        plane = wide[:, :width]  # strided rows, no copy
        assert not plane.flags.c_contiguous
        name = os.path.basename(path)
        found = detector.detect(plane)
        if not found:
            print(f"{name} none")
        for d in found:
            corners = " ".join(f"{v:.4f}" for v in d.corners.ravel())
            print(f"{name} {d.model} {corners} inliers={d.inliers} confidence={d.confidence:.4f}")


if __name__ == "__main__":
    main(sys.argv[1:])
