#!/usr/bin/env python3
"""Seed corpora for the fuzz targets other than the index reader's.

usage: make_seeds.py OUT_DIR OPENCV_DATA_DIR INSPECT_OUTPUT_FILE

Writes OUT_DIR/pgm, OUT_DIR/convert and OUT_DIR/options (generated here,
never committed; .ci/run calls this). INSPECT_OUTPUT_FILE holds the text
of `keygraph inspect` on a real index: its parameter lines become --set seeds.
  pgm:     small P5 files (8 and 16 bit, comments, odd sizes, maxval < 255),
           and the smallest real JPEG of the data directory, whole and cut.
  convert: per pixel format, odd and even widths, padded strides, exact,
           short and long buffers (the 8-byte layout header of
           fuzz_convert.cpp, then pixels).
  options: integers, sizes, NAME=VALUE for every parameter, --draw names.
"""
import os
import random
import struct
import sys

out, data, inspect_text = sys.argv[1], sys.argv[2], sys.argv[3]
rng = random.Random(15)


def write(kind, name, payload):
    os.makedirs(os.path.join(out, kind), exist_ok=True)
    with open(os.path.join(out, kind, name), "wb") as f:
        f.write(payload)


# PGM
def pgm(w, h, maxval=255, comment=False):
    head = b"P5\n" + (b"# keygraph seed\n" if comment else b"") + b"%d %d\n%d\n" % (w, h, maxval)
    n = w * h * (2 if maxval > 255 else 1)
    return head + bytes(rng.randrange(256) for _ in range(n))


write("pgm", "8bit.pgm", pgm(16, 12))
write("pgm", "odd.pgm", pgm(7, 5, comment=True))
write("pgm", "16bit.pgm", pgm(9, 4, maxval=65535))
write("pgm", "maxval100.pgm", pgm(5, 3, maxval=100))
write("pgm", "one.pgm", pgm(1, 1))
jpegs = sorted((os.path.getsize(os.path.join(data, f)), f) for f in os.listdir(data)
               if f.lower().endswith(".jpg"))
if jpegs:
    with open(os.path.join(data, jpegs[0][1]), "rb") as f:
        jpeg = f.read()
    write("pgm", "whole.jpg", jpeg)
    write("pgm", "cut.jpg", jpeg[: len(jpeg) // 2])
# The starts of other formats whose header size image_header.h reads.
pngs = sorted((os.path.getsize(os.path.join(data, f)), f) for f in os.listdir(data)
              if f.lower().endswith(".png"))
if pngs:
    with open(os.path.join(data, pngs[0][1]), "rb") as f:
        write("pgm", "start.png", f.read()[:256])
write("pgm", "header.bmp", b"BM" + bytes(12) + struct.pack("<IiiHH", 40, 300, -200, 1, 8))
write("pgm", "header.tif", b"II*\0" + struct.pack("<IH", 8, 2) + struct.pack("<HHII", 256, 3, 1, 300)
      + struct.pack("<HHII", 257, 4, 1, 200) + bytes(4))
write("pgm", "header.webp", b"RIFF" + struct.pack("<I", 30) + b"WEBPVP8X" + struct.pack("<I", 10)
      + bytes(4) + (299).to_bytes(3, "little") + (199).to_bytes(3, "little"))
write("pgm", "header.pam", b"P7\nWIDTH 300\nHEIGHT 200\nDEPTH 1\nMAXVAL 255\nENDHDR\n")

# convert: format, width (2 bytes), height (2 bytes), extra stride, flags,
# buffer slack (8 = exact), then pixels.
MIN_STRIDE = {0: lambda w: w, 1: lambda w: w, 2: lambda w: w,
              3: lambda w: 4 * ((w + 1) // 2), 4: lambda w: 4 * ((w + 1) // 2)}
for fmt in range(5):
    for w, h, extra, slack in ((33, 7, 0, 8), (64, 4, 3, 8), (17, 9, 5, 0), (2, 2, 0, 15)):
        stride = MIN_STRIDE[fmt](w) + extra
        luma = stride * (h - 1) + MIN_STRIDE[fmt](w)
        frame_extra = stride * ((h + 1) // 2) if fmt in (1, 2) else 0
        header = bytes([fmt, (w - 1) & 255, (w - 1) >> 8, (h - 1) & 255, (h - 1) >> 8, extra, 0,
                        slack])
        pixels = bytes(rng.randrange(256) for _ in range(luma + frame_extra + 8))
        write("convert", "f%d_%dx%d_s%d_b%d" % (fmt, w, h, extra, slack), header + pixels)

# options: NUL-separated arguments.
write("options", "ints", b"\0".join([b"1", b"1073741824", b"999999999999", b"-3", b"0x10", b" 7"]))
write("options", "sizes", b"\0".join([b"640x480", b"32768x1", b"0x0", b"1x32769", b"x"]))
write("options", "draw", b"\0".join([b"out.png", b"a/x.png", b"b/x.png", b"c/y.jpg"]))
assignments = []
in_params = False
with open(inspect_text) as f:
    inspect_lines = f.read().splitlines()
for line in inspect_lines:
    if line.startswith("parameters:"):
        in_params = True
        continue
    if in_params:
        fields = line.split()
        if len(fields) != 2 or "." not in fields[0]:
            break
        assignments.append(("%s=%s" % tuple(fields)).encode())
for i in range(0, len(assignments), 8):
    write("options", "set%02d" % (i // 8), b"\0".join(assignments[i:i + 8]))
print("seeds: %s" % ", ".join("%s %d" % (k, len(os.listdir(os.path.join(out, k))))
                               for k in ("pgm", "convert", "options")))
