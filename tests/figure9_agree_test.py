#!/usr/bin/python3
"""bench/figure9_agree.py on a real figure9 result: a run agrees with itself; a copy whose first
naive/FLAG ratio (with its interval) moved by 20% (or out of its interval), or whose first exponent moved by
0.2, does not; nor do figures taken in another time (process CPU time against wall-clock). A copy whose CPU
copy probe ran at half the rate is named as another machine state.

usage: figure9_agree_test.py AGREE_SCRIPT FIGURE9_JSON SCRATCH_DIR
"""
import copy
import json
import os
import subprocess
import sys

script, results, scratch = sys.argv[1:4]
doc = json.load(open(results))


def agree(other):
    path = os.path.join(scratch, "figure9_agree_other.json")
    with open(path, "w") as f:
        json.dump(other, f)
    return subprocess.run([sys.executable, script, results, path], capture_output=True, text=True)


same = agree(doc)
assert same.returncode == 0, same.stdout + same.stderr
assert "every probe within 1.3x" in same.stdout, same.stdout
# The same figures from a machine whose memory ran at half the rate: told apart as another machine state.
slower = copy.deepcopy(doc)
slower["measurement"]["limits"]["cpu_copy_gb_per_s"] /= 2
r = agree(slower)
assert r.returncode == 0 and "ANOTHER MACHINE STATE (CPU copy more than 1.3x apart)" in r.stdout, r.stdout
moved_ratio = copy.deepcopy(doc)
ratio = moved_ratio["naive_over_flag"][0]
# Moved by 20%, or past its own repeat-run interval where that is wider (a short test run's can be +-30%),
# so that neither run's interval covers the other's estimate.
estimate = ratio["naive_over_flag"]
low, high = ratio.get("repeat_low", ratio["low"]), ratio.get("repeat_high", ratio["high"])
factor = max(1.2, 1.05 * high / estimate, 1.05 * estimate / low)
for key in ("naive_over_flag", "low", "high", "repeat_low", "repeat_high"):
    if key in ratio:
        ratio[key] *= factor
r = agree(moved_ratio)
assert r.returncode == 1 and "DIFFER" in r.stdout, r.stdout
# One figure of n uncovered: calibrated 95% intervals cover n - 1 or fewer with probability 1 - 0.95^n.
n = sum("larger_half" in s["fits"] for s in doc["series"]) + len(doc["naive_over_flag"])
want = f"covered {n - 1} of {n}; intervals that hold cover {0.95 * n:.1f} on average and {n - 1} or fewer for " \
       f"{100 * (1 - 0.95 ** n):.0f}% of pairs"
assert want in r.stdout, (want, r.stdout)
moved_exponent = copy.deepcopy(doc)
fit = next(s["fits"]["larger_half"] for s in moved_exponent["series"] if "larger_half" in s["fits"])
for key in ("exponent", "low", "high", "repeat_low", "repeat_high"):
    if key in fit:
        fit[key] += 0.2
r = agree(moved_exponent)
assert r.returncode == 1 and "DIFFER" in r.stdout, r.stdout
other_time = copy.deepcopy(doc)
for s in other_time["series"]:
    s["time"] = "wall-clock time" if s["time"] == "process CPU time" else "process CPU time"
r = agree(other_time)
assert r.returncode == 1 and "in one run only" in r.stdout, r.stdout
print("figure9_agree: self agrees; a 20% ratio shift, a 0.2 exponent shift, figures in another time and another "
      "machine state are told apart")
