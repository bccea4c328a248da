#!/usr/bin/env python3
"""Downloads the Oxford affine covariant regions set and checks it.

    python3 docs/get-oxford.py [--from DIR] [DEST]

DEST defaults to $KG_DATA_DIR/oxford, else ../shared/data/oxford beside the
checkout (the tests' default, see README: Test data). For each of the 8 subsets the script takes
<subset>.tar.gz from the VGG page (or from DIR with --from, for tarballs
fetched by hand), checks every image's pixels and every homography against
docs/oxford-SHA256SUMS, and writes DEST/<subset>/img1.png .. img6.png (lossless)
and H1to2p .. H1to6p. Nothing is written unless all 8 subsets check out.

The sums cover what does not depend on an encoder: the image as a binary
PNM with the shortest header ("P6\\n<w> <h>\\n255\\n" + RGB bytes, P5 for the
gray boat), and the homography files byte for byte. They were computed from
the copy the project's results were measured on (its SOURCES.md: a mirror of
the VGG files, converted losslessly to PNG). Only the Python 3 standard
library is needed.
"""
import argparse
import hashlib
import os
import shutil
import struct
import sys
import tarfile
import tempfile
import urllib.request
import zlib

URL = "https://www.robots.ox.ac.uk/~vgg/research/affine/det_eval_files/{}.tar.gz"
SUBSETS = ["bark", "bikes", "boat", "graf", "leuven", "trees", "ubc", "wall"]
SUMS = os.path.join(os.path.dirname(os.path.abspath(__file__)), "oxford-SHA256SUMS")


class DataError(Exception):
    pass


def read_sums(path):
    sums = {}
    with open(path) as f:
        for line in f:
            digest, name = line.split()
            sums[name] = digest
    return sums


def parse_pnm(data, name):
    """(magic, width, height, pixels) of a binary 8-bit PGM (P5) or PPM (P6)."""
    fields, pos = [], 0
    while len(fields) < 4:
        while pos < len(data) and data[pos:pos + 1].isspace():
            pos += 1
        if data[pos:pos + 1] == b"#":  # comment to the end of the line
            pos = data.index(b"\n", pos)
            continue
        end = pos
        while end < len(data) and not data[end:end + 1].isspace():
            end += 1
        if end == pos:
            raise DataError(f"{name}: truncated PNM header")
        fields.append(data[pos:end])
        pos = end
    pos += 1  # the single whitespace byte before the pixels
    magic, width, height, maxval = fields[0], int(fields[1]), int(fields[2]), int(fields[3])
    if magic not in (b"P5", b"P6") or maxval != 255:
        raise DataError(f"{name}: not an 8-bit binary PGM/PPM ({magic!r}, maxval {maxval})")
    channels = 3 if magic == b"P6" else 1
    pixels = data[pos:pos + width * height * channels]
    if len(pixels) != width * height * channels:
        raise DataError(f"{name}: {len(pixels)} pixel bytes, expected {width * height * channels}")
    return magic, width, height, pixels


def canonical_pnm(magic, width, height, pixels):
    return magic + b"\n%d %d\n255\n" % (width, height) + pixels


def png(width, height, channels, pixels):
    """A lossless 8-bit gray or RGB PNG (no row filters)."""
    def chunk(kind, body):
        return struct.pack(">I", len(body)) + kind + body + struct.pack(">I", zlib.crc32(kind + body))

    row = width * channels
    raw = b"".join(b"\0" + pixels[y * row:(y + 1) * row] for y in range(height))
    header = struct.pack(">IIBBBBB", width, height, 8, 2 if channels == 3 else 0, 0, 0, 0)
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header) + chunk(b"IDAT", zlib.compress(raw, 9)) +
            chunk(b"IEND", b""))


def tarball(subset, source_dir, work):
    if source_dir:
        path = os.path.join(source_dir, subset + ".tar.gz")
        if not os.path.isfile(path):
            raise DataError(f"{path}: no such file")
        return path
    path = os.path.join(work, subset + ".tar.gz")
    url = URL.format(subset)
    print(f"downloading {url}", file=sys.stderr)
    try:
        with urllib.request.urlopen(url, timeout=60) as r, open(path, "wb") as out:
            shutil.copyfileobj(r, out)
    except OSError as e:
        raise DataError(f"{url}: {e}")
    return path


def convert_subset(subset, archive, sums, out_dir):
    """Checks one subset's files against the sums; writes them to out_dir."""
    members = {}
    try:
        with tarfile.open(archive) as tar:
            for m in tar.getmembers():
                if m.isfile():
                    members[os.path.basename(m.name)] = tar.extractfile(m).read()
    except (OSError, tarfile.TarError) as e:
        raise DataError(f"{archive}: {e}")
    os.makedirs(out_dir)
    for i in range(1, 7):
        for ext in ("ppm", "pgm"):
            if f"img{i}.{ext}" in members:
                break
        else:
            raise DataError(f"{archive}: no img{i}.ppm or img{i}.pgm")
        name = f"{subset}/img{i}.{ext}"
        magic, width, height, pixels = parse_pnm(members[f"img{i}.{ext}"], name)
        digest = hashlib.sha256(canonical_pnm(magic, width, height, pixels)).hexdigest()
        if sums.get(name) != digest:
            raise DataError(f"{name}: pixels do not match docs/oxford-SHA256SUMS "
                            f"(sha256 {digest}, expected {sums.get(name, 'no entry')})")
        with open(os.path.join(out_dir, f"img{i}.png"), "wb") as f:
            f.write(png(width, height, 3 if magic == b"P6" else 1, pixels))
    for i in range(2, 7):
        name = f"{subset}/H1to{i}p"
        data = members.get(f"H1to{i}p")
        if data is None:
            raise DataError(f"{archive}: no H1to{i}p")
        if sums.get(name) != hashlib.sha256(data).hexdigest():
            raise DataError(f"{name}: does not match docs/oxford-SHA256SUMS")
        with open(os.path.join(out_dir, f"H1to{i}p"), "wb") as f:
            f.write(data)


def main():
    # The tests' default (CMakeLists.txt): ../shared/data beside the checkout.
    repo = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    default_root = os.environ.get("KG_DATA_DIR") or os.path.join(os.path.dirname(repo), "shared", "data")
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("dest", nargs="?", default=os.path.join(default_root, "oxford"),
                        help="output directory (default: %(default)s)")
    parser.add_argument("--from", dest="source", metavar="DIR",
                        help="read <subset>.tar.gz from DIR instead of downloading")
    args = parser.parse_args()
    dest = os.path.abspath(args.dest)
    if os.path.exists(dest):
        print(f"get-oxford: {dest} exists; remove it first or give another directory", file=sys.stderr)
        return 1
    sums = read_sums(SUMS)
    os.makedirs(os.path.dirname(dest), exist_ok=True)
    # Everything goes to a temporary directory beside DEST, renamed at the end.
    work = tempfile.mkdtemp(prefix=".oxford-", dir=os.path.dirname(dest))
    try:
        for subset in SUBSETS:
            convert_subset(subset, tarball(subset, args.source, work), sums,
                           os.path.join(work, "oxford", subset))
            print(f"{subset}: 6 images and 5 homographies match", file=sys.stderr)
        shutil.copy(SUMS, os.path.join(work, "oxford", "SHA256SUMS.pixels"))
        os.rename(os.path.join(work, "oxford"), dest)
    except DataError as e:
        print(f"get-oxford: {e}", file=sys.stderr)
        return 1
    finally:
        shutil.rmtree(work, ignore_errors=True)
    print(f"Oxford set in {dest}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
