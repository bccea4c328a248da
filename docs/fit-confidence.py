#!/usr/bin/env python3
"""Fits the detection confidence model (src/core/pose/confidence.h) and reports
precision against recall by confidence threshold.

  fit-confidence.py [--appearance] TUNE/synth-detections.csv [REPORT/synth-detections.csv]

Each CSV is written by `keygraph eval --synth DIR --methods keygraph --out
OUT`. The logistic model is fitted (Newton's method, a small L2 penalty)
on the first file only, keygraph rows, every index size; a detection is
right when it is of the frame's sign with every corner within 10 px. It
prints the coefficients as C++ for kConfidenceModel, then for each file and
index size the share of signs found and the false detections per frame at
a series of thresholds. Standard library only (no numpy on the CI image).
"""
import csv
import math
import sys


def features(row):
    inliers = max(1, int(row["inliers"]))
    out = [
        1.0,
        math.log(inliers),
        min(int(row["inlier_keygraphs"]), 50) / 10.0,
        min(float(row["verification_z"]), 40.0) / 10.0,
        float(row["score"]) - float(row["chance"]),
        float(row["rms_error"]),
    ]
    if WITH_APPEARANCE:
        # The z-score and the support above chance measure the same thing;
        # fitted together the z-score's weight comes out negative, which
        # would make a better-verified pose less trusted. The appearance
        # model leaves it out (weight 0).
        del out[3]
        out.append(float(row["appearance"]))
    return out


def coefficients(w):
    # The weights in ConfidenceModel's order (verification_z 0 when left out).
    return w[:3] + [0.0] + w[3:] if WITH_APPEARANCE else w


# With --appearance, the model with the appearance correlation (indexes of
# format 6.2, kConfidenceModel); without, the one for detections that have
# none (kConfidenceModelNoAppearance).
WITH_APPEARANCE = False
NAMES = ["bias", "log_inliers", "inlier_keygraphs", "verification_z", "score_over_chance",
         "rms_error", "appearance"]


def solve(a, b):
    n = len(b)
    m = [row[:] + [b[i]] for i, row in enumerate(a)]
    for c in range(n):
        p = max(range(c, n), key=lambda r: abs(m[r][c]))
        m[c], m[p] = m[p], m[c]
        for r in range(n):
            if r != c and m[c][c] != 0:
                f = m[r][c] / m[c][c]
                for k in range(c, n + 1):
                    m[r][k] -= f * m[c][k]
    return [m[i][n] / m[i][i] for i in range(n)]


def fit(xs, ys, l2=1e-2, rounds=50):
    w = [0.0] * len(xs[0])
    for _ in range(rounds):
        grad = [l2 * v for v in w]
        hess = [[(l2 if i == j else 0.0) for j in range(len(w))] for i in range(len(w))]
        for x, y in zip(xs, ys):
            z = sum(a * b for a, b in zip(w, x))
            p = 1.0 / (1.0 + math.exp(-max(-30.0, min(30.0, z))))
            for i in range(len(w)):
                grad[i] += (p - y) * x[i]
                for j in range(len(w)):
                    hess[i][j] += p * (1 - p) * x[i] * x[j]
        step = solve(hess, grad)
        w = [a - b for a, b in zip(w, step)]
        if max(abs(s) for s in step) < 1e-9:
            break
    return w


def read(path):
    with open(path, newline="") as f:
        rows = [r for r in csv.DictReader(f) if r["method"] == "keygraph"]
    if WITH_APPEARANCE:
        rows = [r for r in rows if float(r["appearance"]) >= 0.0]
    return rows


def frames_per_size(rows_path):
    # synth-cases.csv beside the detections: frames and signs per index size.
    cases = rows_path.replace("synth-detections.csv", "synth-cases.csv")
    out = {}
    with open(cases, newline="") as f:
        for r in csv.DictReader(f):
            if r["method"] != "keygraph":
                continue
            n = out.setdefault(r["index_size"], [0, 0])
            n[0] += 1
            n[1] += int(r["sign"]) >= 0
    return out


def report(path, w):
    rows = read(path)
    totals = frames_per_size(path)
    print(f"\n{path}")
    print("index  threshold  found %  false/frame  precision")
    for size in sorted(totals, key=int):
        frames, signs = totals[size]
        sized = [r for r in rows if r["index_size"] == size]
        scored = [(1.0 / (1.0 + math.exp(-sum(a * b for a, b in zip(w, features(r))))),
                   r["right"] == "1") for r in sized]
        for t in (0.0, 0.3, 0.5, 0.7, 0.8, 0.9):
            kept = [right for c, right in scored if c >= t]
            right = sum(kept)
            wrong = len(kept) - right
            precision = right / len(kept) if kept else 1.0
            print(f"{size:>5}  {t:9.1f}  {100.0 * right / max(1, signs):7.1f}  "
                  f"{wrong / max(1, frames):11.3f}  {precision:9.3f}")


def main():
    global WITH_APPEARANCE
    args = sys.argv[1:]
    if args and args[0] == "--appearance":
        WITH_APPEARANCE = True
        args = args[1:]
    if not args:
        print(__doc__.strip().splitlines()[2], file=sys.stderr)
        return 2
    sys.argv[1:] = args
    rows = read(sys.argv[1])
    xs = [features(r) for r in rows]
    ys = [1.0 if r["right"] == "1" else 0.0 for r in rows]
    w = fit(xs, ys)
    print(f"fitted on {len(rows)} detections ({int(sum(ys))} right) of {sys.argv[1]}")
    name = "kConfidenceModel" if WITH_APPEARANCE else "kConfidenceModelNoAppearance"
    print(f"inline constexpr ConfidenceModel {name} = {{" +
          ", ".join(f"{v:.4f}" for v in coefficients(w)) + "};  // " +
          ", ".join(NAMES[:len(coefficients(w))]))
    for path in sys.argv[1:]:
        report(path, w)
    return 0


if __name__ == "__main__":
    sys.exit(main())
