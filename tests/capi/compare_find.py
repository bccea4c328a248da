#!/usr/bin/env python3
"""Holds a binding's program to the C++ API's corners.

  compare_find.py [--expect FRAME=MODEL]... [--tolerance PX]
                  --reference CMD... --candidate CMD...

Runs both commands (each prints "FRAME MODEL X0 Y0 .. Y3 inliers=N
confidence=C" per detection, or "FRAME none": tests/capi/find.c), and fails
unless they found the same models in the same frames, every corner within
the tolerance (0.01 px), the same inlier counts, and each --expect'ed model
in its frame. Prints the candidate's output.
"""
import subprocess
import sys


def parse(text, who):
    found = {}
    for line in text.splitlines():
        fields = line.split()
        if len(fields) == 2 and fields[1] == "none":
            found.setdefault(fields[0], [])
            continue
        if len(fields) != 12 or not fields[10].startswith("inliers="):
            sys.exit(f"compare_find: {who}: unexpected line: {line!r}")
        corners = [float(v) for v in fields[2:10]]
        found.setdefault(fields[0], []).append(
            (fields[1], corners, int(fields[10].split("=")[1])))
    return found


def run(command, who):
    result = subprocess.run(command, capture_output=True, text=True, check=False)
    if result.returncode != 0:
        sys.exit(f"compare_find: {who} failed ({result.returncode}): {' '.join(command)}\n"
                 f"{result.stdout}{result.stderr}")
    return result.stdout


def main(argv):
    expects, tolerance, reference, candidate = [], 0.01, [], []
    target = None
    i = 0
    while i < len(argv):
        arg = argv[i]
        if target is None and arg == "--expect":
            frame, _, model = argv[i + 1].partition("=")
            expects.append((frame, model))
            i += 2
            continue
        if target is None and arg == "--tolerance":
            tolerance = float(argv[i + 1])
            i += 2
            continue
        if arg == "--reference" and target is None:
            target = reference
        elif arg == "--candidate":
            target = candidate
        elif target is not None:
            target.append(arg)
        else:
            sys.exit(f"compare_find: unexpected argument {arg!r}")
        i += 1
    if not reference or not candidate:
        sys.exit("usage: compare_find.py [--expect FRAME=MODEL]... --reference CMD... --candidate CMD...")

    ref_text = run(reference, "reference")
    out_text = run(candidate, "candidate")
    sys.stdout.write(out_text)
    ref, out = parse(ref_text, "reference"), parse(out_text, "candidate")
    problems = []
    if sorted(ref) != sorted(out):
        problems.append(f"frames differ: reference {sorted(ref)}, candidate {sorted(out)}")
    worst = 0.0
    for frame in sorted(set(ref) & set(out)):
        a, b = ref[frame], out[frame]
        if [d[0] for d in a] != [d[0] for d in b]:
            problems.append(f"{frame}: models {[d[0] for d in a]} (reference) vs {[d[0] for d in b]}")
            continue
        for (model, ca, ia), (_, cb, ib) in zip(a, b):
            error = max(abs(x - y) for x, y in zip(ca, cb))
            worst = max(worst, error)
            if error > tolerance:
                problems.append(f"{frame} {model}: corners differ by {error:.4f} px")
            if ia != ib:
                problems.append(f"{frame} {model}: {ib} inliers, reference {ia}")
    for frame, model in expects:
        if model not in [d[0] for d in out.get(frame, [])]:
            problems.append(f"{frame}: {model} not found")
    for p in problems:
        print(f"compare_find: {p}", file=sys.stderr)
    if problems:
        return 1
    print(f"compare_find: same detections as the C++ API, corners within {worst:.4f} px "
          f"(tolerance {tolerance})")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
