#!/usr/bin/python3
"""Synthetic results files for the `bokehbench compare` CLI tests, from known distributions.

usage: compare_fixtures.py OUT_DIR
Every point's samples are lognormal (3% spread) around a known median, 15 samples in 15 rounds, and
the calibration probes likewise, in wall time and in process CPU time (twice the wall time: two
threads); the variants change one thing each:
  base.json       the baseline
  same.json       the same distributions, other draws
  slower.json     one point (naive N:9) 1.5x slower, probes unchanged: a regression
  machine2x.json  every point AND every probe 2x slower: another machine, no regression once normalised
  contended.json  wall times 1.3-2.4x and noisy (other processes on the cores), CPU times unchanged
  work.json       one point's work counters changed, times the same: an algorithmic change
  device.json     another device name (another machine: information, exit 0)
  othercpu.json   slower.json's regression, measured on another CPU model (information, exit 0)
  schema1.json    schema_version 1
  points.json     one point missing
  skipped.json    one point skipped instead of measured
  malformed.json  a point without samples_ms
  notjson.json    not JSON at all
  gbench.json     a Google Benchmark file
"""
import copy
import json
import math
import pathlib
import random
import sys

ROUNDS = 15


def draws(rng, median, n=ROUNDS, spread=0.03):
    return [median * math.exp(rng.gauss(0, spread)) for _ in range(n)]


def work(taps):
    return {"passes": {"coc": {"taps": taps / 10, "bytes_read": 4e5, "bytes_written": 3e5},
                       "filter": {"taps": taps, "bytes_read": 1e6, "bytes_written": 5e5}},
            "taps": taps * 1.1, "taps_per_pixel": taps * 1.1 / 30000}


def contention(rng, values):
    """Wall times on a machine shared with other processes: each sample 1.3x to 2.4x longer."""
    return [v * rng.uniform(1.3, 2.4) for v in values]


def point(rng, method, backend, n, median_ms, scale=1.0, contended=False):
    wall = draws(rng, median_ms * scale)
    cpu = draws(rng, 2 * median_ms * scale)
    return {"id": f"{method}/{backend}/hoops/200x150/N:{n}/k:2/f32", "method": method, "backend": backend,
            "scene": "hoops", "width_px": 200, "height_px": 150, "N": n, "k": 2, "max_radius_px": n - 1,
            "precision": "f32", "buffer_scale": 1, "options": {}, "max_coc_px": n - 1,
            "samples_ms": contention(rng, wall) if contended else wall, "samples_cpu_ms": cpu,
            "sample_rounds": list(range(ROUNDS)), "frames_per_sample": 4, "work": work(1e6 * n)}


def document(seed, scale=1.0, slow=None, contended=False):
    rng = random.Random(seed)
    probes = {}
    for name, ms in (("gpu_copy", 20.0), ("gpu_fma", 30.0), ("cpu_copy", 5.0), ("cpu_fma", 8.0)):
        per_round = draws(rng, ms * scale)
        probes[name] = {"ms_per_round": contention(rng, per_round) if contended else per_round,
                        "cpu_ms_per_round": draws(rng, 2 * ms * scale),
                        "ms": {"median": sorted(per_round)[ROUNDS // 2]}, "drift": 0.1, "bytes": 1e6, "flops": 0}
    points = []
    for method in ("naive", "flag"):
        for backend in ("gpu", "cpu"):
            for n, ms in ((5, 4.0), (9, 9.0)):
                p = point(rng, method, backend, n, ms, scale, contended)
                if slow and p["id"] == slow[0]:
                    for key in ("samples_ms", "samples_cpu_ms"):
                        p[key] = [x * slow[1] for x in p[key]]
                points.append(p)
    return {"schema": "bokehbench.figure9", "schema_version": 2,
            "context": {"date_utc": "2026-11-30T00:00:00Z", "git_commit": f"fixture{seed}", "cpu_model": "test CPU",
                        "cpu_cores": 2, "lp_num_threads": "unset",
                        "device": {"index": 0, "name": "llvmpipe (LLVM 15.0.6, 256 bits)", "type": "cpu",
                                   "driver_info": "Mesa 22.3.6", "vendor_id": 65541, "device_id": 0}},
            "status": "complete", "config": {"sizes": [5, 9], "quick": True},
            "measurement": {"rounds": ROUNDS, "probes": probes}, "points": points, "skipped": [], "elapsed_s": 1.0}


def main(out):
    out = pathlib.Path(out)
    out.mkdir(parents=True, exist_ok=True)
    naive9 = "naive/gpu/hoops/200x150/N:9/k:2/f32"
    files = {"base": document(1), "same": document(2), "slower": document(3, slow=(naive9, 1.5)),
             "machine2x": document(4, scale=2.0), "contended": document(11, contended=True)}
    changed = document(5)
    changed["points"][1]["work"]["passes"]["filter"]["taps"] *= 2
    files["work"] = changed
    device = document(6)
    device["context"]["device"]["name"] = "NVIDIA H200"
    files["device"] = device
    othercpu = document(3, slow=(naive9, 1.5))
    othercpu["context"]["cpu_model"] = "another CPU"
    files["othercpu"] = othercpu
    old = document(7)
    old["schema_version"] = 1
    files["schema1"] = old
    fewer = document(8)
    fewer["points"].pop()
    files["points"] = fewer
    skipped = document(9)
    gone = skipped["points"].pop(0)
    skipped["skipped"].append({k: gone[k] for k in ("id", "method", "backend")} | {"reason": "over the memory budget"})
    files["skipped"] = skipped
    broken = document(10)
    del broken["points"][2]["samples_ms"]
    files["malformed"] = broken
    for name, doc in files.items():
        (out / f"{name}.json").write_text(json.dumps(doc, indent=1))
    (out / "notjson.json").write_text("this is not JSON {\n")
    (out / "gbench.json").write_text(json.dumps({"context": {}, "benchmarks": []}))
    print(f"wrote {len(files) + 2} files to {out}")


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    main(sys.argv[1])
