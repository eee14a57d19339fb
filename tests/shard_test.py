#!/usr/bin/python3
"""Three shards of a sweep, run at once as separate processes into one results store, against the
unsharded sweep: together the same set of points, each once; merged into one file that validates
against the sweep schema and that compare reads; the store holds the three shard runs.

usage: shard_test.py BOKEHBENCH WORKDIR SCHEMA_DIR VALIDATE_JSON_PY
       shard_test.py auto BOKEHBENCH WORKDIR SHARD_FLAG EXPECTED_SHARD EXPECTED_SWEEP_ID

A small CPU-only figure9 (naive and FLAG at N = 5, 9, 13: three pairs, one a shard), so that the four
runs take seconds.

auto: one shard run with --shard SHARD_FLAG (auto or auto/N) in the environment the caller set (a
scheduler's variables, set by CTest through `cmake -E env`): its results say config.shard
EXPECTED_SHARD and context.sweep_id EXPECTED_SWEEP_ID; the same task run again into the same store
(a shard given twice) is kept as 'duplicate', with a warning naming the first run, and counted once.
"""
import json
import pathlib
import shutil
import subprocess
import sys


def run(cmd, ok=(0,)):
    done = subprocess.run(cmd, capture_output=True, text=True, timeout=300)
    assert done.returncode in ok, f"{' '.join(map(str, cmd))}: exit {done.returncode}\n{done.stdout}\n{done.stderr}"
    return done


def quick_sweep(bokehbench, work):
    """The smallest figure9 with naive/FLAG pairs: CPU only, N = 5, 9, 13 at 96x64, one thread."""
    return [bokehbench, "figure9", "--quick", "--backends", "cpu", "--sizes", "5", "9", "13", "--width", "96",
            "--height", "64", "--budget-s", "1", "--no-plot", "--cpu-threads", "1", "--reference-cache",
            str(work / "cache")]


def main(bokehbench, workdir, schema_dir, validate):
    work = pathlib.Path(workdir)
    shutil.rmtree(work, ignore_errors=True)
    work.mkdir(parents=True)
    store = work / "shards.sqlite"
    sweep = quick_sweep(bokehbench, work)
    # The unsharded sweep first (it also fills the reference cache the shards share).
    run(sweep + ["--out-dir", str(work / "whole"), "--no-store"])
    unsharded = str(work / "whole" / "figure9.json")
    procs = [subprocess.Popen(sweep + ["--shard", f"{i}/3", "--out-dir", str(work / f"shard{i}"), "--store", str(store)],
                              stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True) for i in (1, 2, 3)]
    for i, p in enumerate(procs, 1):
        out, _ = p.communicate(timeout=300)
        assert p.returncode == 0, f"shard {i}/3: exit {p.returncode}\n{out}"
    whole = json.loads(pathlib.Path(unsharded).read_text())
    everything = {p["id"] for p in whole["points"]} | {p["id"] for p in whole["skipped"]}
    seen = []
    for i in (1, 2, 3):
        doc = json.loads((work / f"shard{i}" / "figure9.json").read_text())
        assert doc["config"]["shard"] == f"{i}/3", doc["config"].get("shard")
        ids = [p["id"] for p in doc["points"]] + [p["id"] for p in doc["skipped"]]
        assert ids, f"shard {i}/3 measured nothing"
        seen += ids
    assert len(seen) == len(set(seen)), f"a point in two shards: {sorted(seen)}"
    assert set(seen) == everything, f"shards {sorted(set(seen))} != unsharded {sorted(everything)}"
    print(f"3 shards: {len(seen)} points, each once, the unsharded sweep's set")
    # Points a command compares stay in one shard: naive and FLAG at each N on each backend.
    for i in (1, 2, 3):
        doc = json.loads((work / f"shard{i}" / "figure9.json").read_text())
        pairs = {(p["backend"], p["N"]) for p in doc["points"]}
        for backend, n in pairs:
            methods = {p["method"] for p in doc["points"] if (p["backend"], p["N"]) == (backend, n)}
            assert methods == {"naive", "flag"}, f"shard {i}: {backend} N={n} has {methods}"

    merged = work / "merged.json"
    run([bokehbench, "merge", *[str(work / f"shard{i}" / "figure9.json") for i in (3, 1, 2)], "--out", str(merged)])
    run(["/usr/bin/python3", validate, str(pathlib.Path(schema_dir) / "sweep.schema.json"), str(merged)])
    doc = json.loads(merged.read_text())
    assert {p["id"] for p in doc["points"]} == {p["id"] for p in whole["points"]}
    # figure9's derived figures over all merged points (merge_derived_test.py checks their values).
    assert doc["derived_recomputed"] is True, doc.get("merged_note")
    assert {(r["backend"], r["N"]) for r in doc["naive_over_flag"]} == {(r["backend"], r["N"]) for r in whole["naive_over_flag"]}
    assert {(c["method"], c["backend"]) for c in doc["series"]} == {(c["method"], c["backend"]) for c in whole["series"]}
    # compare reads it: a verdict (0 or 2; never 1, an error, or 3, not comparable).
    done = run([bokehbench, "compare", unsharded, str(merged)], ok=(0, 2, 4))
    print(f"merged: valid, compare exit {done.returncode}")
    # A shard missing is named.
    done = run([bokehbench, "merge", str(work / "shard1" / "figure9.json"), str(work / "shard2" / "figure9.json"), "--out",
                str(work / "partial.json")], ok=(1,))
    assert "shard 3/3 is missing" in done.stderr, done.stderr
    # The store has the three shard runs.
    done = run([bokehbench, "history", "list", "--store", str(store)])
    for i in (1, 2, 3):
        assert f" {i}/3 " in done.stdout, done.stdout
    assert "3 runs" in done.stdout, done.stdout
    print("store: the three shard runs")


def auto_main(bokehbench, workdir, shard_flag, expected_shard, expected_sweep_id):
    work = pathlib.Path(workdir)
    shutil.rmtree(work, ignore_errors=True)
    work.mkdir(parents=True)
    store = work / "store.sqlite"
    sweep = quick_sweep(bokehbench, work) + ["--shard", shard_flag, "--out-dir", str(work / "run"), "--store",
                                             str(store)]
    run(sweep)
    doc = json.loads((work / "run" / "figure9.json").read_text())
    assert doc["config"].get("shard") == expected_shard, doc["config"].get("shard")
    assert doc["context"].get("sweep_id") == expected_sweep_id, doc["context"].get("sweep_id")
    assert doc["points"], f"shard {expected_shard} measured nothing"
    print(f"--shard {shard_flag}: config.shard {expected_shard}, context.sweep_id {expected_sweep_id}")
    # The same task again (a shard given twice): kept, marked, counted once.
    done = run(sweep)
    assert f"shard {expected_shard} of this sweep is already in the results store" in done.stderr, done.stderr
    assert "(run 1)" in done.stderr, done.stderr
    listed = run([bokehbench, "history", "list", "--store", str(store)]).stdout
    rows = [line.split() for line in listed.splitlines()[2:] if line.strip()]  # after the count and the header
    assert [(r[0], r[4], r[5]) for r in rows] == [("1", expected_shard, "complete"), ("2", expected_shard, "duplicate")], listed
    point = doc["points"][0]["id"]
    series = run([bokehbench, "history", "series", "--store", str(store), "--point", point]).stdout
    values = [line.split() for line in series.splitlines()[2:] if line.strip()]
    assert len(values) == 1 and values[0][-1] == "1", series  # one commit, of 1 run
    print(f"the same shard twice: run 2 kept as duplicate, {point}'s series counts run 1 only")


if __name__ == "__main__":
    if len(sys.argv) == 7 and sys.argv[1] == "auto":
        auto_main(*sys.argv[2:])
    elif len(sys.argv) == 5:
        main(*sys.argv[1:])
    else:
        sys.exit(__doc__)
