"""What the Python tests of the keygraph tool share: running it, counting failed
checks, reading its JSON lines and the 8-bit PGM files it reads and writes.

The tests import it from their own folder (Python puts a script's folder first
on its path), so they still run as `python3 tests/cli/NAME.py ...`.
"""
import json
import subprocess
import sys


class Checks:
    """Failed checks of one test script; finish() ends the script with them."""

    def __init__(self, name, verbose=False):
        self.name = name
        self.verbose = verbose  # also print the checks that pass
        self.failures = []

    def __call__(self, ok, what):
        if not ok:
            self.failures.append(what)
            print("FAIL: " + what, file=sys.stderr)
        elif self.verbose:
            print("ok: " + what)

    def finish(self):
        """Ends the script: exit status 1 naming the count of failed checks, else 0."""
        if self.failures:
            sys.exit("%s: %d check(s) failed" % (self.name, len(self.failures)))
        print("%s: all checks passed" % self.name)
        sys.exit(0)


def run_tool(command, *args, timeout):
    """The finished process of COMMAND (a list: the tool, maybe after an emulator) with ARGS."""
    return subprocess.run([*command, *args], capture_output=True, text=True, timeout=timeout)


def json_lines(text):
    return [json.loads(line) for line in text.splitlines()]


def read_pgm(path):
    """(width, height, pixels) of an 8-bit binary PGM without comments (keygraph writes none)."""
    with open(path, "rb") as f:
        data = f.read()
    fields = data.split(maxsplit=4)
    assert fields[0] == b"P5" and fields[3] == b"255", path
    width, height = int(fields[1]), int(fields[2])
    return width, height, data[len(data) - width * height:]


def write_pgm_crop(path, pixels, width, x0, y0, w, h):
    """Writes the w x h window at (x0, y0) of an image WIDTH pixels wide as a PGM file."""
    rows = b"".join(pixels[(y0 + y) * width + x0:(y0 + y) * width + x0 + w] for y in range(h))
    with open(path, "wb") as f:
        f.write(b"P5\n%d %d\n255\n" % (w, h) + rows)
