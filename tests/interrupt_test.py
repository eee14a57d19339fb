#!/usr/bin/python3
"""Interruption and concurrency leave only valid results files (issue 11).

usage: interrupt_test.py BOKEHBENCH WORKDIR

A small CPU-only figure9 sweep is run to completion once, then killed at random points with SIGTERM
and SIGKILL, interrupted by a group-wide SIGINT (sent twice at once, as `timeout -s INT` and a
terminal do), run as two processes (--processes 2) and interrupted while the second measures, and
run twice at once into the same --out-dir. After each, every *.json file in the
folder must parse, and figure9.json must still be a complete result: a run never replaces a complete
result with a partial one. The results store they all append to holds only whole runs (complete or
interrupted), the concurrent ones included. Bounded: about a dozen runs of a few seconds each.
"""
import json
import os
import pathlib
import random
import shutil
import signal
import subprocess
import sys
import time


def check_folder(out_dir, what):
    files = sorted(out_dir.glob("*.json"))
    assert files, f"{what}: no results files at all"
    for path in files:
        try:
            doc = json.loads(path.read_text())
        except ValueError as e:
            sys.exit(f"FAIL {what}: {path.name} is not valid JSON: {e}")
        if path.name == "figure9.json":
            assert doc["status"] == "complete", f"{what}: figure9.json has status {doc['status']}"
            assert doc["points"], f"{what}: figure9.json has no points"
        if path.name.endswith("_gbench.json") or path.name.endswith("_gbench.partial.json"):
            assert "benchmarks" in doc and "context" in doc, f"{what}: {path.name} lacks gbench keys"
        if path.name == "figure9.partial.json":
            assert doc["status"] in ("partial", "interrupted"), f"{what}: partial file has status {doc['status']}"
    return [p.name for p in files]


def main(bokehbench, workdir):
    work = pathlib.Path(workdir)
    shutil.rmtree(work, ignore_errors=True)
    out_dir = work / "out"
    cache = work / "cache"
    rng = random.Random(11)

    def command(seed):
        return [bokehbench, "figure9", "--quick", "--backends", "cpu", "--methods", "naive", "--sizes", "5", "9",
                "--width", "96", "--height", "64", "--budget-s", "1", "--no-plot", "--cpu-threads", "1",
                "--seed", str(seed), "--out-dir", str(out_dir), "--reference-cache", str(cache)]

    start = time.monotonic()
    done = subprocess.run(command(1), capture_output=True, text=True, timeout=120)
    duration = time.monotonic() - start
    assert done.returncode == 0, done.stdout + done.stderr
    print(f"complete run: {duration:.1f} s; files {check_folder(out_dir, 'complete run')}")

    # Killed at random points: before, during and after measuring, while writing.
    for i, sig in enumerate([signal.SIGTERM, signal.SIGKILL] * 4):
        proc = subprocess.Popen(command(100 + i), stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        delay = rng.uniform(0.05, duration * 1.1)
        time.sleep(delay)
        proc.send_signal(sig)
        out, _ = proc.communicate(timeout=120)
        files = check_folder(out_dir, f"{sig.name} after {delay:.2f} s")
        print(f"{sig.name} after {delay:.2f} s: exit {proc.returncode}; files {files}")
        if sig == signal.SIGTERM and proc.returncode == 1:
            assert "interrupted after" in out, out

    # A group-wide SIGINT, twice at once, once measuring has begun: finished points are kept, with a message.
    proc = subprocess.Popen(command(7), stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                            start_new_session=True)
    lines = []
    for line in proc.stdout:
        lines.append(line)
        if line.startswith("[  1/"):
            break
    os.killpg(proc.pid, signal.SIGINT)
    os.killpg(proc.pid, signal.SIGINT)
    out = "".join(lines) + proc.communicate(timeout=120)[0]
    assert proc.returncode == 1, f"exit {proc.returncode} (130 is the fast exit a single Ctrl-C must not take):\n{out}"
    assert "interrupted after" in out and "figure9.partial.json" in out, out
    partial = json.loads((out_dir / "figure9.partial.json").read_text())
    assert partial["status"] == "interrupted", partial["status"]
    print(f"group SIGINT: exit 1, partial file with {len(partial['points'])} points; files "
          f"{check_folder(out_dir, 'group SIGINT')}")

    # A run of two processes (--processes 2) interrupted while its second measures, by a group-wide SIGINT (a
    # terminal's Ctrl-C) and by a SIGTERM to the first process alone (which passes it on): the finished process's
    # rounds are kept, joined with what the second measured, in the partial file.
    for group in (True, False):
        proc = subprocess.Popen(command(300) + ["--processes", "2"], stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                                text=True, start_new_session=True)
        lines, second = [], False
        for line in proc.stdout:
            lines.append(line)
            second = second or line.startswith("== process 2 of 2")
            if second and line.startswith("[  1/"):
                break
        if group:
            os.killpg(proc.pid, signal.SIGINT)
        else:
            proc.send_signal(signal.SIGTERM)
        out = "".join(lines) + proc.communicate(timeout=120)[0]
        how = "group SIGINT" if group else "SIGTERM to the first process"
        assert proc.returncode == 1 and "interrupted after" in out, f"{how}: exit {proc.returncode}\n{out}"
        partial = json.loads((out_dir / "figure9.partial.json").read_text())
        owner = partial["measurement"]["round_process"]
        assert partial["status"] == "interrupted" and owner.count(0) >= 5, (how, partial["status"], owner)
        print(f"two processes, {how} during the second: exit 1, partial file with rounds by process {owner}; files "
              f"{check_folder(out_dir, how)}")

    # Two runs into one folder at once: both finish and every file is valid.
    procs = [subprocess.Popen(command(200 + i), stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
             for i in range(2)]
    for p in procs:
        out, _ = p.communicate(timeout=180)
        assert p.returncode == 0, out
    print(f"two concurrent runs: both complete; files {check_folder(out_dir, 'concurrent runs')}")
    # Temporaries of writers killed mid-write are removed by the next run.
    stale = sorted(p.name for p in out_dir.glob("*.tmp.*"))
    assert not stale, f"stale temporaries left: {stale}"
    check_store(out_dir / "history.sqlite")
    print("interruption and concurrency: every results file valid")


def check_store(path):
    """Every run in the results store is whole: complete or interrupted, never half-written (a killed
    append leaves nothing), each with its points and samples; the interrupted run is there as such."""
    import sqlite3
    db = sqlite3.connect(path)
    assert db.execute("PRAGMA integrity_check").fetchone()[0] == "ok"
    runs = db.execute("SELECT id, status FROM runs").fetchall()
    statuses = [s for _, s in runs]
    assert set(statuses) <= {"complete", "interrupted"}, statuses
    assert statuses.count("complete") >= 3, statuses  # the first run and the two concurrent ones
    assert "interrupted" in statuses, statuses  # the group SIGINT's
    for run_id, status in runs:
        points = db.execute("SELECT COUNT(*) FROM points WHERE run_id = ?", (run_id,)).fetchone()[0]
        samples = db.execute("SELECT COUNT(*) FROM samples WHERE run_id = ?", (run_id,)).fetchone()[0]
        assert points == samples, (run_id, points, samples)
        if status == "complete":
            assert points == 2, (run_id, points)  # naive at N = 5 and 9
    print(f"results store: {len(runs)} runs ({statuses.count('complete')} complete, "
          f"{statuses.count('interrupted')} interrupted), each whole")


if __name__ == "__main__":
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    main(sys.argv[1], sys.argv[2])
