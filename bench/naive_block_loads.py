#!/usr/bin/python3
"""Loads of naive's blocked gather on lavapipe (shaders/naive/gather.comp, OUTPUTS_X x OUTPUTS_Y = 8 x 4),
counted from the shader's loop bounds: per block, every sample row j in [-n, n + 3] inside the frame loads
the columns i in [-span, span + 7] inside the frame, span the largest disc reach over the block's 4 output
rows. Each such load is one per-lane buffer load, which lavapipe executes as scalar loads, so the pass's time
follows this count (results/README.md, Figure 9: "Why naive's slope is below 2").

usage: bench/naive_block_loads.py [FIGURE9_JSON]
  prints the loads per frame at each N of figure9's default sizes (800x600, k = 2) and their growth exponent
  over the larger half; with a figure9 results file, also its naive GPU gather pass's median ms per million
  loads at each N (flat when the pass is bound by its loads).
"""
import json
import math
import sys

import numpy as np

W, H, K, BX, BY = 800, 600, 2, 8, 4
SIZES = [9, 33, 57, 81, 105, 129, 153]


def block_origins(extent, outputs):
    """The first output of every invocation along one axis (block g // k of `outputs` outputs at stride k, phase g % k)."""
    count = -(-extent // (outputs * K)) * K
    origins = [(g // K) * (outputs * K) + g % K for g in range(count)]
    return np.array([o for o in origins if o < extent])


def loads(size_n):
    n = (size_n - 1) // 2
    r2 = (n * K) ** 2
    reach = lambda j: -1 if abs(j) > n else math.isqrt(r2 - (j * K) ** 2) // K  # disc_reach_layer at the max radius
    xs, ys = block_origins(W, BX), block_origins(H, BY)
    total = 0
    for j in range(-n, n + BY):
        span = max(reach(j - l) for l in range(BY))
        if span < 0:
            continue
        rows = np.count_nonzero((ys + j * K >= 0) & (ys + j * K < H))
        columns = sum(np.count_nonzero((xs + i * K >= 0) & (xs + i * K < W)) for i in range(-span, span + BX))
        total += rows * columns
    return total


def main(argv):
    counts = {n: loads(n) for n in SIZES}
    larger = SIZES[len(SIZES) // 2:]
    slope = np.polyfit(np.log(larger), np.log([counts[n] for n in larger]), 1)[0]
    gather = {}
    if argv:
        doc = json.load(open(argv[0]))
        for p in doc["points"]:
            if p["method"] == "naive" and p["backend"] == "gpu" and "gather" in p.get("samples_pass_ms", {}):
                gather[p["N"]] = float(np.median(p["samples_pass_ms"]["gather"]))
    for n in SIZES:
        line = f"N = {n:3d}: {counts[n] / 1e6:8.2f} M loads a frame"
        if n in gather:
            line += f", gather {gather[n]:7.1f} ms, {gather[n] / counts[n] * 1e6:.2f} ms per M loads"
        print(line)
    print(f"growth exponent of the loads over N = {larger[0]}-{larger[-1]}: {slope:.3f}")


if __name__ == "__main__":
    main(sys.argv[1:])
