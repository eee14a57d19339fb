#!/usr/bin/python3
"""merge recomputes a sweep's derived figures over the merged points with the command's own code: a real
figure9 run's points split into three shards (naive and FLAG of one N and backend together, as --shard
keeps them, the CPU baselines with the GPU points of their N), their derived figures deleted, merged; the
merged file's naive/FLAG ratios, FLAG/baseline ratios, growth exponents and headlines equal those the figure9 command derived over the same points in the same run (the same
samples: deterministic, the bootstrap is seeded), and equal the unsharded file merged alone (1/1).
The same for adaptive's speed-ups (off and on of one configuration in one shard). A sweep merge knows no
derivation for says so in its output and JSON.

usage: merge_derived_test.py BOKEHBENCH WORKDIR FIGURE9_JSON ADAPTIVE_JSON
"""
import copy
import json
import pathlib
import shutil
import subprocess
import sys

DERIVED = ("series", "naive_over_flag", "headlines", "baseline_series", "flag_over_baseline")


def run(cmd, ok=(0,)):
    done = subprocess.run(cmd, capture_output=True, text=True, timeout=120)
    assert done.returncode in ok, f"{' '.join(map(str, cmd))}: exit {done.returncode}\n{done.stdout}\n{done.stderr}"
    return done


def figures(doc):
    """The derived figures, in an order that does not depend on the points' order in the file."""
    key = lambda r: (r["backend"], r["N"])
    out = {k: copy.deepcopy(doc.get(k)) for k in DERIVED}
    out["naive_over_flag"].sort(key=key)
    out["headlines"]["wall_time"]["naive_over_flag"].sort(key=key)
    out["headlines"]["unsettled"].sort()  # listed in the points' order
    out["headlines"]["wall_time"]["unsettled"].sort()
    return out


def shard_file(work, base, name, shard, points, derived=DERIVED):
    doc = copy.deepcopy(base)
    for k in derived:
        doc.pop(k, None)  # merge must compute them, not carry a shard's
    doc["config"]["shard"] = shard
    doc["points"] = points
    doc["skipped"] = [s for s in base["skipped"]] if shard.startswith("1/") else []
    # figure9's CPU baselines go with the GPU points of their N, as --shard keeps them
    gpu_n = {p["N"] for p in points if p["backend"] == "gpu"}
    for key in ("baselines", "skipped_baselines"):
        if key in base:
            doc[key] = [b for b in base[key] if b["N"] in gpu_n]
    path = work / name
    path.write_text(json.dumps(doc))
    return str(path)


def adaptive_check(bokehbench, work, adaptive_json):
    base = json.loads(pathlib.Path(adaptive_json).read_text())
    assert base["comparisons"], "the adaptive run has no comparisons to check against"
    off_of = lambda p: p["id"].replace('/adaptive:"on"', "")  # off and on of one configuration together
    keys = sorted({off_of(p) for p in base["points"]})
    assert len(keys) >= 3, keys
    shards = [[p for p in base["points"] if keys.index(off_of(p)) % 3 == i] for i in range(3)]
    files = [shard_file(work, base, f"adaptive{i + 1}.json", f"{i + 1}/3", shards[i], ("comparisons",)) for i in range(3)]
    merged = work / "adaptive_merged.json"
    out = run([bokehbench, "merge", files[1], files[2], files[0], "--out", str(merged)]).stdout
    assert "derived figures recomputed over all points" in out, out
    got = sorted(json.loads(merged.read_text())["comparisons"], key=lambda c: c["off_id"])
    want = sorted(base["comparisons"], key=lambda c: c["off_id"])
    assert got == want, "adaptive: merged shards' comparisons differ from the command's own"
    print(f"adaptive, 3 shards: {len(got)} speed-ups (paired, with intervals) equal the command's")


def main(bokehbench, workdir, figure9_json, adaptive_json):
    work = pathlib.Path(workdir)
    shutil.rmtree(work, ignore_errors=True)
    work.mkdir(parents=True)
    base = json.loads(pathlib.Path(figure9_json).read_text())
    assert base["naive_over_flag"] and base["series"], "the run has no derived figures to check against"
    assert base.get("flag_over_baseline") or base.get("skipped_baselines"), "the run has no CPU baseline"
    groups = sorted({(p["backend"], p["N"]) for p in base["points"]})
    assert len(groups) >= 3, f"too few (backend, N) groups for three shards: {groups}"
    shards = [[p for p in base["points"] if groups.index((p["backend"], p["N"])) % 3 == i] for i in range(3)]
    files = [shard_file(work, base, f"shard{i + 1}.json", f"{i + 1}/3", shards[i]) for i in range(3)]
    merged = work / "merged.json"
    out = run([bokehbench, "merge", files[2], files[0], files[1], "--out", str(merged)]).stdout
    assert "derived figures recomputed over all points" in out, out
    doc = json.loads(merged.read_text())
    assert doc["derived_recomputed"] is True and "were recomputed" in doc["merged_note"], doc["merged_note"]
    whole_path = shard_file(work, base, "whole.json", "1/1", base["points"])
    run([bokehbench, "merge", whole_path, "--out", str(work / "whole_merged.json")])
    whole = json.loads((work / "whole_merged.json").read_text())
    got, by_command, unsharded = figures(doc), figures(base), figures(whole)
    for k in DERIVED:
        assert got[k] == by_command[k], f"{k}: merged shards differ from the command's own figures"
        assert got[k] == unsharded[k], f"{k}: merged shards differ from the unsharded points merged alone"
    print(f"3 shards ({[len(s) for s in shards]} points): {len(got['naive_over_flag'])} naive/FLAG ratios and "
          f"{len(got['series'])} curves' exponents equal the command's and the unsharded computation's")

    adaptive_check(bokehbench, work, adaptive_json)

    # A sweep merge has no derivation for: merged, and said so.
    other = copy.deepcopy(base)
    other["schema"] = "bokehbench.unknown_sweep"
    for k in DERIVED:
        other.pop(k, None)
    other["config"]["shard"] = "1/1"
    path = work / "unknown.json"
    path.write_text(json.dumps(other))
    out = run([bokehbench, "merge", str(path), "--out", str(work / "unknown_merged.json")]).stdout
    assert "NOT recomputed" in out, out
    doc = json.loads((work / "unknown_merged.json").read_text())
    assert doc["derived_recomputed"] is False and "NOT recomputed" in doc["merged_note"], doc["merged_note"]
    assert "naive_over_flag" not in doc
    print("an unknown sweep: merged, derived figures NOT recomputed, said in output and JSON")


if __name__ == "__main__":
    if len(sys.argv) != 5:
        sys.exit(__doc__)
    main(*sys.argv[1:])
