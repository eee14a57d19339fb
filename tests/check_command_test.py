#!/usr/bin/python3
"""Runs `bokehbench check METHOD --json FILE` and holds its output to what it states.

usage: check_command_test.py STATUS JSON COMMAND...

The command must exit with STATUS; every line between the header and the counts must read
"PASS|FAIL|SKIP  name: reason"; the counts line must agree with those lines and with the JSON; every
check must be there; a PASS whose line states "X <= B" must have X <= B (and a FAIL "X > B"), the same
numbers as the JSON's value and bound; the accuracy check's rank must lie within what it ranked.
"""
import json
import math
import re
import subprocess
import sys

CHECKS = ["in-focus image unchanged", "uniform image stays uniform", "energy conserved away from the borders",
          "bad input: NaN colour", "bad input: infinite colour", "bad input: colour 1e30", "bad input: NaN depth",
          "bad input: depth 0.0001 m (huge CoC)", "no out-of-bounds access (validation layer)",
          "memory declared = memory allocated", "error vs the exact reference", "GPU matches its CPU reference"]
COUNTS = re.compile(r"^(\d+) passed, (\d+) failed, (\d+) skipped$")
NUMBER = r"([-+]?(?:\d+\.?\d*(?:e[-+]?\d+)?|nan|inf))"


def fail(message, output):
    print(output)
    sys.exit(message)


def main(status, json_path, command):
    run = subprocess.run(command, capture_output=True, text=True)
    output = run.stdout + run.stderr
    if run.returncode != status:
        fail(f"expected exit status {status}, got {run.returncode}", output)
    lines = run.stdout.splitlines()
    if not lines or not lines[0].startswith("check "):
        fail("the first line should name the method checked", output)
    results = {}
    counts = None
    for line in lines[1:]:
        if line.startswith("wrote "):
            continue
        if (found := COUNTS.match(line)):
            counts = tuple(int(n) for n in found.groups())
            continue
        found = re.match(r"^(PASS|FAIL|SKIP)  (.+?): (.+)$", line)
        name = next((c for c in CHECKS if line[6:].startswith(c + ": ")), None)
        if not found or name is None:
            fail(f"not a check line: {line!r}", output)
        results[name] = (found.group(1), line[6 + len(name) + 2:])
    missing = [c for c in CHECKS if c not in results]
    if missing:
        fail(f"checks missing from the output: {missing}", output)
    tally = tuple(sum(1 for s, _ in results.values() if s == which) for which in ("PASS", "FAIL", "SKIP"))
    if counts != tally:
        fail(f"the counts line says {counts}, the check lines {tally}", output)
    if (status == 0) != (tally[1] == 0):
        fail(f"exit status {status} with {tally[1]} failed checks", output)

    doc = json.load(open(json_path))
    if (doc["passed"], doc["failed"], doc["skipped"]) != tally:
        fail(f"the JSON's counts differ from the output's {tally}", output)
    by_name = {c["name"]: c for c in doc["checks"]}
    for name, (verdict, reason) in results.items():
        entry = by_name.get(name)
        if entry is None or entry["status"] != verdict or entry["reason"] != reason:
            fail(f"the JSON disagrees with the line of '{name}': {entry}", output)
        # "... X <= B ..." (PASS) or "... X > B ..." (FAIL): the numbers it judged by, and the JSON's.
        if (found := re.search(NUMBER + r" (<=|>) " + NUMBER, reason)):
            value, relation, bound = float(found.group(1)), found.group(2), float(found.group(3))
            holds = value <= bound
            if holds != (relation == "<=") or holds != (verdict == "PASS"):
                fail(f"'{name}': {verdict} but {value} {relation} {bound}", output)
            # JSON has no NaN or Inf: a non-finite number is written as null.
            def same(printed, written):
                if written is None:
                    return not math.isfinite(printed)
                return math.isclose(printed, written, rel_tol=1e-2, abs_tol=1e-12)
            if not (same(value, entry["value"]) and same(bound, entry["bound"])):
                fail(f"'{name}': the line says {value} and {bound}, the JSON {entry['value']} and {entry['bound']}",
                     output)
    verdict, reason = results["error vs the exact reference"]
    if verdict == "PASS":
        found = re.search(r"RMSE " + NUMBER + r" .*: (\d+)(?:st|nd|rd|th) of (\d+) by RMSE", reason)
        if not found:
            fail(f"the accuracy line names no RMSE and rank: {reason}", output)
        rmse, rank, ranked = float(found.group(1)), int(found.group(2)), int(found.group(3))
        details = by_name["error vs the exact reference"]["details"]
        if not (math.isfinite(rmse) and rmse >= 0 and 1 <= rank <= ranked and ranked >= 2 and
                details["rank"] == rank and len(details["rmse_interior_vs_energy_sum"]) == ranked):
            fail(f"the accuracy rank does not add up: RMSE {rmse}, {rank} of {ranked}, JSON {details}", output)
        errors = sorted(details["rmse_interior_vs_energy_sum"].values())
        if not math.isclose(errors[rank - 1], rmse, rel_tol=1e-3):
            fail(f"RMSE {rmse} is not the {rank}th smallest of {errors}", output)
    print(output)
    print(f"check: {tally[0]} passed, {tally[1]} failed, {tally[2]} skipped, as stated")


if __name__ == "__main__":
    if len(sys.argv) < 4:
        sys.exit(__doc__)
    main(int(sys.argv[1]), sys.argv[2], sys.argv[3:])
