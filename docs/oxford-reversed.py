#!/usr/bin/env python3
"""Writes a `keygraph eval --truth` manifest of Oxford pairs taken backwards.

    python3 docs/oxford-reversed.py [OXFORD_DIR] [OUT_DIR]

For the zoom subsets (bark, boat), imgN (N = 2..6) is the model and img1 the
scene: img1 shows the middle of imgN 1.1 to 4.2 times larger, the case of
an object seen larger than its model image (views.max_scale,
docs/RESULTS.md, "Views larger than the model"). The ground truth is the
inverse of H1toNp. Writes OUT_DIR/oxford-reversed.jsonl and
OUT_DIR/oxford-reversed-models.json (absolute image paths) and prints each
pair's scale. OXFORD_DIR defaults to $KG_DATA_DIR/oxford, else
../shared/data/oxford; OUT_DIR to the current directory. Only the Python 3
standard library is needed.
"""
import json
import math
import os
import sys


def inverse(m):
    a, b, c, d, e, f, g, h, i = m
    cof = [e * i - f * h, -(d * i - f * g), d * h - e * g,
           -(b * i - c * h), a * i - c * g, -(a * h - b * g),
           b * f - c * e, -(a * f - c * d), a * e - b * d]
    # The adjugate (transposed cofactors) is the inverse up to scale;
    # normalised so that its last entry is 1, as the Oxford files are.
    adj = [cof[0], cof[3], cof[6], cof[1], cof[4], cof[7], cof[2], cof[5], cof[8]]
    return [v / adj[8] for v in adj]


def main():
    data = os.environ.get("KG_DATA_DIR", os.path.join("..", "shared", "data"))
    oxford = os.path.abspath(sys.argv[1] if len(sys.argv) > 1 else os.path.join(data, "oxford"))
    out = sys.argv[2] if len(sys.argv) > 2 else "."
    models, lines = {}, []
    for subset in ("bark", "boat"):
        for n in range(2, 7):
            path = os.path.join(oxford, subset, "H1to%dp" % n)
            try:
                with open(path) as f:
                    h = [float(v) for v in f.read().split()]
            except OSError as e:
                sys.exit("oxford-reversed.py: %s" % e)
            if len(h) != 9:
                sys.exit("oxford-reversed.py: %s: not a 3x3 matrix" % path)
            back = inverse(h)  # imgN -> img1
            name = "%s%d" % (subset, n)
            models[name] = os.path.join(oxford, subset, "img%d.png" % n)
            lines.append({"scene": os.path.join(oxford, subset, "img1.png"), "search": [name],
                          "instances": [{"model": name, "homography": back}]})
            scale = math.sqrt(abs(back[0] * back[4] - back[1] * back[3]))
            print("%s: img%d seen %.2fx larger in img1" % (name, n, scale))
    os.makedirs(out, exist_ok=True)
    with open(os.path.join(out, "oxford-reversed.jsonl"), "w") as f:
        f.write("".join(json.dumps(line) + "\n" for line in lines))
    with open(os.path.join(out, "oxford-reversed-models.json"), "w") as f:
        json.dump(models, f, indent=1)


if __name__ == "__main__":
    main()
