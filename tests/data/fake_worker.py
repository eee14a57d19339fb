#!/usr/bin/python3
"""A stand-in for a build's `--serve` worker, for the `bokehbench ab` tests: it speaks the protocol of
bench/runner/paired.hpp with times and work counters known in advance, so the coordinator's verdicts
and exit codes can be checked exactly, without Vulkan or timing noise.

What it does depends on the name it is started under (tests make symlinks to it):
  ..._base      two points, 4 ms and 8 ms a frame, 1000 taps each
  ..._slower    the same, the second point 1.5x slower
  ..._work      the same times, the first point's taps doubled (an algorithmic change)
  ..._other     two other points (nothing in common with base)
  ..._protocol  protocol 99
  ..._fails     the second point answers with an error
Each sample's time has a deterministic ripple of +-1% (the same in every build), so the paired
log-ratios are exactly log(slowdown).
"""
import json
import os
import sys

kind = os.path.basename(sys.argv[0]).rsplit("_", 1)[-1]
ids = ["naive/cpu/fake/8x8/N:5/k:2/f32", "flag/cpu/fake/8x8/N:5/k:2/f16"]
if kind == "other":
    ids = ["spiral/cpu/fake/8x8/N:5/k:2/f32", "hexagon/cpu/fake/8x8/N:5/k:2/f32"]
frame_ms = [4.0, 8.0 * (1.5 if kind == "slower" else 1.0)]
points = []
for i, pid in enumerate(ids):
    taps = 2000.0 if kind == "work" and i == 0 else 1000.0
    points.append({"id": pid, "method": pid.split("/")[0], "backend": "cpu", "skip": "",
                   "work": {"taps": taps, "passes": {"filter": {"taps": taps}}}})
hello = {"protocol": 99 if kind == "protocol" else 1,
         "context": {"git_commit": "fake-" + kind, "cpu_model": "test CPU", "cpu_cores": 2, "device": None},
         "points": points}
print(json.dumps({"hello": hello}), flush=True)
samples = 0
for line in sys.stdin:
    request = json.loads(line)
    if request["op"] == "quit":
        break
    i = request["point"]
    if kind == "fails" and i == 1:
        print(json.dumps({"error": "fake failure on point 1"}), flush=True)
        continue
    ripple = 1 + 0.01 * ((samples % 3) - 1)
    samples += 1
    ms = frame_ms[i] * (ripple if request["op"] == "sample" else 1)
    print(json.dumps({"frame_ms": ms, "cpu_ms": ms}), flush=True)
