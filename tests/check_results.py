#!/usr/bin/python3
"""Checks on a command's results file beyond its JSON schema: what the schema cannot say.

usage: check_results.py gbench|adaptive|injected FILE
"""
import json
import sys


def gbench(d):
    """Google Benchmark's JSON: names stable across runs (compare.py matches them)."""
    b = d["benchmarks"]
    assert b and d["context"]["library_build_type"]
    unstable = [x["name"] for x in b if "iterations:" in x["name"] or "repetitions:" in x["name"]]
    assert not unstable, f"names must be stable across runs for compare.py: {unstable}"
    print(len(b), "gbench entries")


def adaptive(d):
    """Every method that declares `adaptive` is compared, off against on, and the modes keep their promises."""
    declared = {m["name"] for m in d["methods"] if any(o["key"] == "adaptive" for o in m["options"])}
    compared = {c["method"] for c in d["comparisons"]}
    assert {"naive", "flag"} <= declared == compared, (declared, compared)
    assert len(d["comparisons"]) == len(d["points"]) // 2, "every on point has its off twin"
    for c in d["comparisons"]:
        assert c["speedup"] > 0
        if c["method"] == "naive":
            assert c["error_on"] == c["error_off"], c
        if c["method"] == "flag":
            assert c["memory_saved_fraction"] > 0, c
            assert c["scene_stats"]["layers"] < c["scene_stats"]["layers_worst_case"], c
    print(len(d["comparisons"]), "comparisons of", sorted(compared))


def injected(d):
    """--inject-slowdown-pct 25 is recorded, and every sample's frames are a multiple of 4 (25% is whole frames)."""
    assert d["config"]["injected_slowdown_pct"] == 25, d["config"]
    assert d["measurement"]["extra_work_fraction"] == 0.25
    frames = [p["frames_per_sample"] for p in d["points"]]
    assert frames and all(x % 4 == 0 for x in frames), frames
    print("frames per sample", frames)


if __name__ == "__main__":
    checks = {"gbench": gbench, "adaptive": adaptive, "injected": injected}
    if len(sys.argv) != 3 or sys.argv[1] not in checks:
        sys.exit(__doc__)
    with open(sys.argv[2]) as f:
        checks[sys.argv[1]](json.load(f))
