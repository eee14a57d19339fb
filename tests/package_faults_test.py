#!/usr/bin/env python3
"""Faulty method packages in a sweep (tests/data/packages/faulty_*): each fault skips its own points
with a reason naming it, and every other point is measured and written.

  faulty_zero_buffer  a buffer sized max(0, N - 30): N = 21 skipped naming the buffer, N = 41 measured
  faulty_nan          writes NaN: skipped, "non-finite"
  faulty_runaway      a pass that runs far past its estimate: the watchdog names the pass, the GPU
                      points after it are skipped (the device cannot be stopped), the run ends and
                      writes its results (exit 0) instead of hanging
and, beside them, scaled_scratch: buffer_scales swept by tradeoff and buffers, its memory following the scale.

usage: package_faults_test.py BOKEHBENCH PACKAGES_DIR OUT_DIR
"""
import json
import subprocess
import sys
from pathlib import Path

exe, packages, out = sys.argv[1], Path(sys.argv[2]), Path(sys.argv[3])
common = ["--resolutions", "64x48", "--budget-s", "1", "--backends", "gpu", "--processes", "1", "--no-plot", "--no-store"]


def sweep(name, *args):
    run = subprocess.run([exe, "figure9", *common, "--out-dir", str(out / name), *args], capture_output=True, text=True,
                         timeout=240)
    assert run.returncode == 0, f"{name}: exit {run.returncode}\n{run.stdout[-2000:]}\n{run.stderr[-2000:]}"
    doc = json.loads((out / name / "figure9.json").read_text())
    skipped = {s["id"]: s["reason"] for s in doc["skipped"]}
    return {p["id"] for p in doc["points"]}, skipped


def expect(condition, what):
    if not condition:
        sys.exit(f"FAIL: {what}")
    print("ok:", what.split(":")[0])


measured, skipped = sweep("sizes_and_nan", "-N", "21", "41", "--methods", str(packages / "faulty_zero_buffer"),
                          str(packages / "faulty_nan"))
zero21 = "faulty_zero_buffer/gpu/hoops/64x48/N:21/k:2/f32"
expect("buffers[0] ('scratch'): elements 'max(0, N - 30)' is 0" in skipped.get(zero21, ""),
       f"a buffer of no elements skips its point naming the buffer: {skipped}")
expect(measured == {"faulty_zero_buffer/gpu/hoops/64x48/N:41/k:2/f32"}, f"the other point is measured: {measured}")
nan = [r for i, r in skipped.items() if i.startswith("faulty_nan/")]
expect(len(nan) == 2 and all("non-finite values (NaN or infinite)" in r for r in nan),
       f"NaN output skips the package's points, saying so: {nan}")

measured, skipped = sweep("runaway", "-N", "21", "--methods", "naive", str(packages / "faulty_runaway"),
                          "--watchdog-s", "2")
runaway = skipped.get("faulty_runaway/gpu/hoops/64x48/N:21/k:2/f32", "")
expect("pass 'spin' of 1 frame at 64x48 ran past the watchdog" in runaway, f"the watchdog names the pass: {skipped}")
naive = "naive/gpu/hoops/64x48/N:21/k:2/f32"
expect(naive in measured or "ran past the watchdog" in skipped.get(naive, ""),
       f"the built-in is measured before the runaway, or skipped saying why after it: {measured} {skipped}")

# Not a fault: a package declaring buffer_scales is swept at each by tradeoff and by buffers, its declared
# memory following the scale (ceil(64 / s) x ceil(48 / s) RGBA32F texels) and measured as allocated.
for command in ("tradeoff", "buffers"):
    run = subprocess.run([exe, command, "-N", "21", "--resolutions", "64x48", "--budget-s", "1", "--processes", "1",
                          "--no-plot", "--no-store", "--methods", str(packages / "scaled_scratch"), "--out-dir",
                          str(out / command)], capture_output=True, text=True, timeout=240)
    assert run.returncode == 0, run.stdout[-2000:] + run.stderr[-2000:]
    doc = json.loads((out / command / f"{command}.json").read_text())
    scratch = {p["buffer_scale"]: p["memory"]["details"]["scratch_bytes"] for p in doc["points"]}
    expect(scratch == {s: -(-64 // s) * -(-48 // s) * 16 for s in (1, 2, 4)},
           f"{command}: a package's buffer_scales are swept, its memory following the scale: {scratch}")
    expect(all(p["memory"]["allocated_bytes"] == p["memory"]["bytes"] for p in doc["points"]),
           f"{command}: declared memory = allocated at every scale")
