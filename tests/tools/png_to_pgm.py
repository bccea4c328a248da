#!/usr/bin/env python3
"""Converts an 8-bit grayscale, non-interlaced PNG into a binary PGM (P5).

    png_to_pgm.py IN.png OUT.pgm

Standard library only (zlib), so the tests' PGM frames can be made at build
time on any host, the cross-builds' included, without OpenCV. Other PNGs
(colour, palette, 16-bit, interlaced) are refused with one error line. The
output is written to a temporary file and renamed: whole or not at all.
"""
import os
import struct
import sys
import zlib

PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"


def fail(message):
    sys.exit(f"png_to_pgm: {message}")


def chunks(data, name):
    """Yields (type, payload) of each chunk, checking lengths and CRCs."""
    pos = len(PNG_SIGNATURE)
    while pos + 12 <= len(data):
        (length,) = struct.unpack(">I", data[pos : pos + 4])
        kind = data[pos + 4 : pos + 8]
        payload = data[pos + 8 : pos + 8 + length]
        crc_bytes = data[pos + 8 + length : pos + 12 + length]
        if len(payload) != length or len(crc_bytes) != 4:
            fail(f"{name}: truncated {kind!r} chunk")
        if zlib.crc32(kind + payload) != struct.unpack(">I", crc_bytes)[0]:
            fail(f"{name}: bad CRC in the {kind!r} chunk")
        yield kind, payload
        if kind == b"IEND":
            return
        pos += 12 + length
    fail(f"{name}: no IEND chunk (truncated file)")


def paeth(a, b, c):
    p = a + b - c
    pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
    if pa <= pb and pa <= pc:
        return a
    return b if pb <= pc else c


def unfilter(raw, width, height, name):
    """The gray pixels of the scanlines (one filter byte each, 1 byte a pixel)."""
    if len(raw) != height * (width + 1):
        fail(f"{name}: {len(raw)} bytes of scanlines, expected {height * (width + 1)}")
    out = bytearray(width * height)
    previous = bytearray(width)
    for y in range(height):
        start = y * (width + 1)
        kind = raw[start]
        line = bytearray(raw[start + 1 : start + 1 + width])
        if kind == 1:  # Sub
            for x in range(1, width):
                line[x] = (line[x] + line[x - 1]) & 0xFF
        elif kind == 2:  # Up
            for x in range(width):
                line[x] = (line[x] + previous[x]) & 0xFF
        elif kind == 3:  # Average
            for x in range(width):
                left = line[x - 1] if x else 0
                line[x] = (line[x] + ((left + previous[x]) >> 1)) & 0xFF
        elif kind == 4:  # Paeth
            for x in range(width):
                left = line[x - 1] if x else 0
                up_left = previous[x - 1] if x else 0
                line[x] = (line[x] + paeth(left, previous[x], up_left)) & 0xFF
        elif kind != 0:
            fail(f"{name}: scanline {y} has filter type {kind}")
        out[y * width : (y + 1) * width] = line
        previous = line
    return out


def read_gray_png(path):
    with open(path, "rb") as f:
        data = f.read()
    if not data.startswith(PNG_SIGNATURE):
        fail(f"{path}: not a PNG file")
    header, idat = None, []
    for kind, payload in chunks(data, path):
        if kind == b"IHDR":
            header = struct.unpack(">IIBBBBB", payload)
        elif kind == b"IDAT":
            idat.append(payload)
    if header is None:
        fail(f"{path}: no IHDR chunk")
    width, height, depth, colour, _, _, interlace = header
    if depth != 8 or colour != 0 or interlace != 0:
        fail(
            f"{path}: bit depth {depth}, colour type {colour}, interlace {interlace}; "
            "only 8-bit grayscale non-interlaced PNGs are converted"
        )
    try:
        raw = zlib.decompress(b"".join(idat))
    except zlib.error as e:
        fail(f"{path}: image data does not inflate ({e})")
    return width, height, unfilter(raw, width, height, path)


def main(argv):
    if len(argv) != 3:
        print("usage: png_to_pgm.py IN.png OUT.pgm", file=sys.stderr)
        return 2
    try:
        width, height, pixels = read_gray_png(argv[1])
    except OSError as e:
        fail(f"{argv[1]}: {e.strerror}")
    temporary = f"{argv[2]}.tmp{os.getpid()}"
    try:
        with open(temporary, "wb") as f:
            f.write(b"P5\n%d %d\n255\n" % (width, height))
            f.write(pixels)
        os.replace(temporary, argv[2])
    except OSError as e:
        if os.path.exists(temporary):
            os.remove(temporary)
        fail(f"{argv[2]}: {e.strerror}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
