#!/usr/bin/python3
"""The README's Slurm recipe, run as written on a throwaway one-node cluster into a throwaway PostgreSQL
store (issue 45).

usage: slurm_recipe_test.py BOKEHBENCH WORKDIR README SCHEMA_DIR VALIDATE_JSON_PY

Run under tests/with_postgres.py and tests/with_slurm.py (CTest does): they give BOKEH_TEST_POSTGRES_HOST
and _USER, and SLURM_CONF / BOKEH_TEST_SLURM_CONF. Without either it skips (exit 77), saying why.

The recipe is the README's lines between '# >>> Slurm recipe' and '# <<< Slurm recipe'. The test changes
only the values of the two variables it sets, BOKEH_SWEEP (the smallest figure9 that still has naive/FLAG
pairs: CPU only, N = 5, 9, 13 at 96x64, one shard a pair, as tests/shard_test.py runs it) and
BOKEH_STORE_URL (a new database on the throwaway server), and runs it with sh in a folder where
build/bokehbench is the binary under test. Then:

  recipe      the array's three tasks and the dependent merge complete; the shards hold the unsharded
              run's points, each once, pairs unsplit; the merged file validates, has the same points and
              its derived figures recomputed, and compare reads it; `history list` and `report` show the
              three shard runs, and each task's log names the run it appended, whose points in the store
              are the ones its shard's file holds, as `history list --points` shows them under the task's job
              (which task measured which point).
  duplicate   the same task run again in the same job (scontrol requeue ARRAY_2): the store never counts
              shard 2/3 twice (`history list` shows it once complete, the repeat marked, as 'duplicate';
              the series of its points count one run).
  cancelled   (a second store and folder, a sweep with a longer budget) task 2 cancelled mid-sweep
              (scancel ARRAY_2 once its partial results exist): tasks 1 and 3 complete and their runs are
              in the store; the dependent merge never runs (DependencyNeverSatisfied); the recipe's merge
              command fails on the missing file and merge of the shards there names "shard 2/3 is
              missing"; task 2 requeued completes the run, and the recipe's merge line (array=ARRAY_2)
              then merges all three.

Waits are bounded (WAIT_S) so that a stuck cluster fails with its queue shown; no timing is asserted.
"""
import json
import os
import pathlib
import re
import shlex
import shutil
import subprocess
import sys
import time

SKIP = 77
WAIT_S = 240  # a bound on any one wait for the cluster, not an expected time
BEGIN, END = "# >>> Slurm recipe", "# <<< Slurm recipe"
SWEEP = "figure9 --quick --backends cpu --sizes 5 9 13 --width 96 --height 64 --no-plot --cpu-threads 1"
QUICK = " --budget-s 1"
# Long enough that task 2 is still measuring when it is cancelled: the targets are out of reach, so each
# task measures for its whole budget (partial results are written from the first rounds on).
SLOW = " --budget-s 10 --target-ratio-pct 0.01 --target-exponent 0.001"


def log(*args):
    print(*args, flush=True)


def run(cmd, ok=(0,), cwd=None, timeout=300):
    done = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout, cwd=cwd)
    assert done.returncode in ok, f"{' '.join(map(str, cmd))}: exit {done.returncode}\n{done.stdout}\n{done.stderr}"
    return done


def recipe_of(readme):
    """The README's Slurm recipe: its lines between the markers, unindented."""
    lines = pathlib.Path(readme).read_text().splitlines()
    begin = [i for i, line in enumerate(lines) if line.strip().startswith(BEGIN)]
    end = [i for i, line in enumerate(lines) if line.strip().startswith(END)]
    assert len(begin) == 1 and len(end) == 1 and begin[0] < end[0], \
        f"{readme}: expected one '{BEGIN}' line and one '{END}' line after it (found {len(begin)} and {len(end)})"
    block = lines[begin[0] + 1:end[0]]
    indent = min(len(line) - len(line.lstrip()) for line in block if line.strip())
    return "\n".join(line[indent:] for line in block) + "\n"


def with_values(recipe, sweep, store_url):
    """The recipe with its two variables' values replaced, nothing else."""
    out = recipe
    for name, value in (("BOKEH_SWEEP", sweep), ("BOKEH_STORE_URL", store_url)):
        pattern = re.compile(rf'(?<![\w$]){name}=("[^"]*"|\'[^\']*\'|[^\s;]+)')
        found = pattern.findall(out)
        assert len(found) == 1, f"the README's Slurm recipe sets {name} {len(found)} times; this test expects once"
        out = pattern.sub(lambda _: f"{name}={shlex.quote(value)}", out)
    return out


def logical_lines(recipe):
    """Commands of the recipe, each with its continuation lines; comments and blank lines left out."""
    out, current = [], ""
    for line in recipe.splitlines():
        if not current and (not line.strip() or line.lstrip().startswith("#")):
            continue
        if line.endswith("\\"):
            current += line + "\n"  # kept as written: inside --wrap='...' the backslash-newline is the job script's
            continue
        out.append(current + line)
        current = ""
    return out


def merge_line(recipe):
    lines = [line for line in logical_lines(recipe) if "--dependency=afterok:" in line]
    assert len(lines) == 1, f"the README's Slurm recipe has {len(lines)} sbatch --dependency=afterok lines; expected 1"
    assert '"$array"' in lines[0] or "$array" in lines[0], "the recipe's merge line does not depend on $array"
    return lines[0]


def merge_command(recipe):
    """The command the recipe's merge job runs (its --wrap)."""
    words = shlex.split(merge_line(recipe).split("#")[0])
    wraps = [w[len("--wrap="):] for w in words if w.startswith("--wrap=")]
    assert len(wraps) == 1, "the recipe's merge line has no --wrap='COMMAND'"
    return wraps[0]


def job_id(text):
    m = re.search(r"^(?:Submitted batch job )?(\d+)(?:;\S+)?$", text.strip().splitlines()[-1] if text.strip() else "")
    assert m, f"no job id in sbatch's output: {text!r}"
    return m.group(1)


def states(*jobs):
    """Each job's (or array task's) state and reason, completed ones included."""
    done = run(["squeue", "--noheader", "--array", "--states=all", "--jobs", ",".join(jobs), "--format=%i|%T|%r"])
    return {line.split("|")[0]: tuple(line.split("|")[1:3]) for line in done.stdout.splitlines() if "|" in line}


def queue_text():
    return run(["squeue", "--array", "--states=all", "--format=%.12i %.10T %.24r %j"], ok=(0, 1)).stdout


def wait_for(what, ready, interval=0.25):
    end = time.monotonic() + WAIT_S
    while time.monotonic() < end:
        got = ready()
        if got:
            return got
        time.sleep(interval)
    raise AssertionError(f"{what}: not within {WAIT_S} s. The queue:\n{queue_text()}")


FINISHED = ("COMPLETED", "FAILED", "CANCELLED", "TIMEOUT", "NODE_FAIL", "OUT_OF_MEMORY", "PREEMPTED", "BOOT_FAIL",
            "DEADLINE")


def wait_finished(work, *jobs):
    """Every job and array task given has finished; returns their states. A job whose dependency can never be
    satisfied fails the wait at once, naming it."""
    def ready():
        s = states(*jobs)
        stuck = [j for j, (state, reason) in s.items() if state == "PENDING" and reason == "DependencyNeverSatisfied"]
        if stuck:
            raise AssertionError(f"{', '.join(stuck)}: dependency never satisfied (a task it waits on failed)\n"
                                 f"{queue_text()}\n{task_logs(work)}")
        return s if s and all(state in FINISHED for state, _ in s.values()) else None
    return wait_for(f"jobs {', '.join(jobs)} to finish", ready)


def task_logs(work):
    return "\n".join(f"--- {p.name}\n{p.read_text(errors='replace')}" for p in sorted(work.glob("slurm-*.out")))


def require_completed(work, got, what):
    bad = {j: s for j, s in got.items() if s[0] != "COMPLETED"}
    assert not bad, f"{what}: {bad}\n{task_logs(work)}"


def points_of(doc):
    return [p["id"] for p in doc["points"]] + [p["id"] for p in doc["skipped"]]


class Store:
    def __init__(self, host, user, name):
        self.host, self.user, self.name = host, user, name
        psql(host, user, "postgres", f"CREATE DATABASE {name}")
        self.url = f"postgresql://{user}@/{name}?host={host}"

    def sql(self, query):
        return [line.split("|") for line in psql(self.host, self.user, self.name, query).splitlines() if line]

    def runs(self):
        """run id -> (shard, status)"""
        return {int(r[0]): (r[1], r[2]) for r in self.sql("SELECT id, shard, status FROM runs ORDER BY id")}

    def points(self, run_id):
        return sorted(r[0] for r in self.sql(f"SELECT point_id FROM points WHERE run_id = {int(run_id)}"))


def psql(host, user, db, query):
    done = run(["psql", "-X", "-q", "-A", "-t", "-v", "ON_ERROR_STOP=1", "-h", host, "-U", user, "-d", db, "-c", query])
    return done.stdout


class Recipe:
    """The README's recipe run once in its own folder."""

    def __init__(self, bokehbench, work, recipe, sweep, store):
        self.bokehbench, self.work, self.recipe, self.sweep, self.store = bokehbench, work, recipe, sweep, store
        shutil.rmtree(work, ignore_errors=True)
        (work / "build").mkdir(parents=True)
        # build/bokehbench, as the recipe names it, is the binary under test.
        os.symlink(os.path.abspath(bokehbench), work / "build" / "bokehbench")

    def submit(self):
        script = ("set -eu\n" + with_values(self.recipe, self.sweep, self.store.url) +
                  'printf "BOKEH_TEST_ARRAY=%s\\n" "$array"\n')
        (self.work / "recipe.sh").write_text(script)
        done = run(["sh", str(self.work / "recipe.sh")], cwd=self.work)
        out = done.stdout.strip().splitlines()
        assert out and out[-1].startswith("BOKEH_TEST_ARRAY="), f"the recipe printed {done.stdout!r}"
        self.array = out[-1].split("=", 1)[1]
        assert re.fullmatch(r"\d+", self.array), f"the recipe's array job id is {self.array!r}"
        self.merge = job_id("\n".join(out[:-1]))
        log(f"recipe submitted: array job {self.array} (tasks 1-3), merge job {self.merge} (afterok:{self.array})")

    def merge_again(self, array):
        """The recipe's merge line, run with $array set to the job (or task) it must wait for."""
        script = f"set -eu\narray={shlex.quote(array)}\n" + merge_line(self.recipe) + "\n"
        (self.work / "merge_again.sh").write_text(script)
        done = run(["sh", str(self.work / "merge_again.sh")], cwd=self.work)
        return job_id(done.stdout)

    def shard_doc(self, i):
        return json.loads((self.work / "results" / f"shard{i}" / "figure9.json").read_text())

    def appended_run(self, task):
        """The run id task TASK's log says it appended (or appended as a duplicate)."""
        text = (self.work / f"slurm-{self.array}_{task}.out").read_text(errors="replace")
        found = re.findall(r"appended (?:run (\d+) \(|as run (\d+) with status)", text)
        assert found, f"task {self.array}_{task}'s log names no run appended to the store:\n{text}"
        return int([a or b for a, b in found][-1])


def check_recipe(r, bokehbench, schema_dir, validate):
    got = wait_finished(r.work, r.array, r.merge)
    require_completed(r.work, got, "the recipe's jobs")
    log(f"array {r.array}: tasks {sorted(j for j in got if j != r.merge)} and merge job {r.merge} completed")
    whole = json.loads((r.work / "whole" / "figure9.json").read_text())
    everything = set(points_of(whole))
    seen = []
    for i in (1, 2, 3):
        doc = r.shard_doc(i)
        assert doc["config"]["shard"] == f"{i}/3", doc["config"].get("shard")
        ids = points_of(doc)
        assert ids, f"shard {i}/3 measured nothing"
        seen += ids
        pairs = {(p["backend"], p["N"]) for p in doc["points"]}
        for backend, n in pairs:
            methods = {p["method"] for p in doc["points"] if (p["backend"], p["N"]) == (backend, n)}
            assert methods == {"naive", "flag"}, f"shard {i}: {backend} N={n} has {methods}"
    assert len(seen) == len(set(seen)), f"a point in two shards: {sorted(seen)}"
    assert set(seen) == everything, f"shards {sorted(set(seen))} != unsharded {sorted(everything)}"
    log(f"3 shards: {len(seen)} points, each once, the unsharded run's set")

    merged = r.work / "results" / "figure9.json"
    assert merged.exists(), f"the merge job wrote no {merged}\n{task_logs(r.work)}"
    run(["/usr/bin/python3", validate, str(pathlib.Path(schema_dir) / "sweep.schema.json"), str(merged)])
    doc = json.loads(merged.read_text())
    ids = [p["id"] for p in doc["points"]]
    assert len(ids) == len(set(ids)) and set(ids) == {p["id"] for p in whole["points"]}, \
        f"merged points {sorted(ids)} != unsharded {sorted(p['id'] for p in whole['points'])}"
    assert doc["derived_recomputed"] is True, doc.get("merged_note")
    assert {(x["backend"], x["N"]) for x in doc["naive_over_flag"]} == {(x["backend"], x["N"]) for x in whole["naive_over_flag"]}
    assert {(c["method"], c["backend"]) for c in doc["series"]} == {(c["method"], c["backend"]) for c in whole["series"]}
    assert sorted(s["shard"] for s in doc["shards"]) == ["1/3", "2/3", "3/3"], doc["shards"]
    done = run([bokehbench, "compare", str(r.work / "whole" / "figure9.json"), str(merged)], ok=(0, 2, 4))
    log(f"merged by the dependent job: valid, the unsharded run's points, derived figures recomputed; compare exit "
        f"{done.returncode}")

    # The store: history list and report show the three shard runs; each task's run holds its shard's points.
    listing = run([bokehbench, "history", "list", "--store", r.store.url]).stdout
    log(listing.rstrip())
    assert "3 runs" in listing, listing
    listed_points = points_listed(run([bokehbench, "history", "list", "--points", "--store", r.store.url]).stdout)
    runs = r.store.runs()
    report = r.work / "report.html"
    run([bokehbench, "report", "--store", r.store.url, "--out", str(report), "--plots-dir", str(r.work / "no_plots"),
         "--permutations", "19"])
    html = report.read_text()
    for i in (1, 2, 3):
        run_id = r.appended_run(i)
        shard, status = runs[run_id]
        assert (shard, status) == (f"{i}/3", "complete"), f"task {i}'s run {run_id} is shard {shard}, {status}"
        assert re.search(rf"^ +{run_id} +\S+ +\S+ +figure9 +{i}/3 +complete ", listing, re.M), \
            f"history list does not show run {run_id} as figure9 shard {i}/3, complete:\n{listing}"
        assert re.search(rf"<tr><td>{run_id}</td>.*?<td>figure9</td><td>{i}/3</td><td>complete</td>", html), \
            f"the report's runs table has no row for run {run_id}, shard {i}/3"
        stored, in_file = r.store.points(run_id), sorted(p["id"] for p in r.shard_doc(i)["points"])
        assert stored == in_file, f"task {i}'s run {run_id} holds {stored}; its shard file {in_file}"
        job, listed = listed_points[run_id]
        assert job == f"slurm:{r.array}" and sorted(listed) == in_file, \
            f"history list --points shows run {run_id} as job {job} with {listed}; expected slurm:{r.array}, {in_file}"
        log(f"task {r.array}_{i} -> run {run_id} (shard {i}/3): {', '.join(stored)}")
    log("history list and the report show the three shard runs; each task's points are its run's")


def points_listed(listing):
    """{run id: (job, [point ids])} from `history list --points`: each run's line, then its job and points indented."""
    out, current = {}, None
    for line in listing.splitlines():
        head = re.match(r"^ +(\d+)  \d{4}-", line)
        if head:
            current = int(head.group(1))
            out[current] = ("", [])
        elif current is not None and line.startswith("       "):
            text = line.strip()
            if text.startswith("job "):
                out[current] = (text[4:], out[current][1])
            else:
                out[current][1].append(text)
    return out


def check_duplicate(r, bokehbench):
    """Task 2 run again in the same job: shard 2/3 is never counted twice."""
    run(["scontrol", "requeue", f"{r.array}_2"])
    run(["scontrol", "update", f"JobId={r.array}_2", "StartTime=now"])  # a requeued job otherwise waits ~2 min
    got = wait_finished(r.work, f"{r.array}_2")
    require_completed(r.work, got, "task 2 requeued")
    runs = r.store.runs()
    second = r.appended_run(2)
    complete = [i for i, (shard, status) in runs.items() if shard == "2/3" and status == "complete"]
    listing = run([bokehbench, "history", "list", "--store", r.store.url]).stdout
    point = sorted(p["id"] for p in r.shard_doc(2)["points"])[0]
    series = run([bokehbench, "history", "series", "--store", r.store.url, "--point", point]).stdout
    rows = [line.split() for line in series.splitlines() if re.match(r"^ +[0-9a-f]{7,}", line)]
    counted = sum(int(row[-1]) for row in rows)
    log(listing.rstrip())
    log(series.rstrip())
    assert len(complete) == 1 and second not in complete, \
        f"shard 2/3 has {len(complete)} complete runs in the store (runs {complete}); the repeat (run {second}) " \
        "should be refused or marked"
    assert counted == 1, f"the series of {point} counts {counted} runs of its commit; shard 2/3 was measured once " \
        "and repeated once"
    log(f"task 2 run twice in job {r.array}: shard 2/3 counted once (the repeat, run {second}: '{runs[second][1]}')")


def check_cancelled(r, bokehbench):
    """Task 2 cancelled mid-sweep; the others' results stay; merge names the missing shard; the rerun completes it."""
    partial = r.work / "results" / "shard2" / "figure9.partial.json"

    def measuring():
        s = states(r.array)
        state = s.get(f"{r.array}_2", ("", ""))[0]
        if state in FINISHED:
            why = "give SLOW a longer --budget-s" if state == "COMPLETED" else "it failed"
            raise AssertionError(f"task 2 finished ({state}) before it could be cancelled mid-sweep: {why}\n"
                                 f"{task_logs(r.work)}")
        return state == "RUNNING" and partial.exists()
    wait_for("task 2 to be measuring (its partial results written)", measuring, interval=0.1)
    run(["scancel", f"{r.array}_2"])
    log(f"scancel {r.array}_2 while it measured ({partial.name} written)")
    got = wait_finished(r.work, *[f"{r.array}_{i}" for i in (1, 2, 3)])
    assert got[f"{r.array}_2"][0] == "CANCELLED", got
    require_completed(r.work, {k: v for k, v in got.items() if k != f"{r.array}_2"}, "tasks 1 and 3")
    merge_state = wait_for("the merge job to be refused its dependency",
                           lambda: (lambda s: s if s[1] == "DependencyNeverSatisfied" or s[0] != "PENDING" else None)(
                               states(r.merge).get(r.merge, ("", ""))))
    assert merge_state == ("PENDING", "DependencyNeverSatisfied"), f"merge job {r.merge}: {merge_state}"
    assert not (r.work / "results" / "figure9.json").exists(), "the merge ran although task 2 was cancelled"
    log(f"tasks 1, 3 completed, 2 cancelled; merge job {r.merge}: {merge_state[1]}")

    # The others' results are in the store; task 2's, if any, is not complete.
    runs = r.store.runs()
    for i in (1, 3):
        run_id = r.appended_run(i)
        assert runs[run_id] == (f"{i}/3", "complete"), f"task {i}'s run {run_id}: {runs[run_id]}"
        assert r.store.points(run_id) == sorted(p["id"] for p in r.shard_doc(i)["points"])
    shard2 = [status for shard, status in runs.values() if shard == "2/3"]
    assert "complete" not in shard2, f"the cancelled task left a complete run: {runs}"
    log(f"store after the cancel: {sorted(runs.values())}")

    # merge: the recipe's command fails on the missing file; the shards there are named missing.
    done = run(["sh", "-c", merge_command(r.recipe)], ok=range(1, 256), cwd=r.work)
    assert re.search(r"(does not exist|No such file)[^\n]*results/shard2/figure9\.json", done.stdout + done.stderr), \
        f"the recipe's merge command, shard 2 missing: exit {done.returncode}\n{done.stdout}{done.stderr}"
    log(f"the recipe's merge command: exit {done.returncode}, {(done.stdout + done.stderr).strip().splitlines()[0]}")
    present = [str(r.work / "results" / f"shard{i}" / "figure9.json") for i in (1, 3)]
    done = run([bokehbench, "merge", *present, "--out", str(r.work / "partial_merge.json")], ok=(1,))
    assert "shard 2/3 is missing" in done.stderr, done.stderr
    log(f"merge of shards 1 and 3: {done.stderr.strip().splitlines()[-1]}")

    # Task 2 again (same job), then the recipe's merge line waiting on it.
    run(["scancel", r.merge])
    run(["scontrol", "requeue", f"{r.array}_2"])
    run(["scontrol", "update", f"JobId={r.array}_2", "StartTime=now"])
    merge = r.merge_again(f"{r.array}_2")
    got = wait_finished(r.work, f"{r.array}_2", merge)
    require_completed(r.work, got, "task 2 rerun and the merge after it")
    runs = r.store.runs()
    rerun = r.appended_run(2)
    assert runs[rerun] == ("2/3", "complete"), f"the rerun's run {rerun}: {runs[rerun]}"
    complete = sorted(shard for shard, status in runs.values() if status == "complete")
    assert complete == ["1/3", "2/3", "3/3"], f"complete runs after the rerun: {complete}"
    doc = json.loads((r.work / "results" / "figure9.json").read_text())
    ids = [p["id"] for p in doc["points"]]
    expected = [p["id"] for i in (1, 2, 3) for p in r.shard_doc(i)["points"]]
    assert sorted(ids) == sorted(expected) and len(ids) == len(set(ids)), (ids, expected)
    log(f"task 2 requeued: run {rerun} complete; merge job {merge} merged {len(ids)} points from the 3 shards")


def main(bokehbench, workdir, readme, schema_dir, validate):
    host, user = os.environ.get("BOKEH_TEST_POSTGRES_HOST"), os.environ.get("BOKEH_TEST_POSTGRES_USER")
    if not host or not user:
        log("SKIP: no PostgreSQL server: run through tests/with_postgres.py (ctest does; apt-get install postgresql)")
        return SKIP
    if not os.environ.get("BOKEH_TEST_SLURM_CONF") or os.environ.get("SLURM_CONF") != os.environ["BOKEH_TEST_SLURM_CONF"]:
        log("SKIP: no throwaway Slurm cluster: run through tests/with_slurm.py (ctest does; apt-get install slurmctld "
            "slurmd slurm-client munge)")
        return SKIP
    for tool in ("psql", "sbatch", "squeue", "scancel", "scontrol"):
        assert shutil.which(tool), f"{tool} is not on PATH"
    bokehbench = os.path.abspath(bokehbench)
    recipe = recipe_of(readme)
    log(f"the README's Slurm recipe:\n{recipe}")
    work = pathlib.Path(workdir).resolve()
    shutil.rmtree(work, ignore_errors=True)
    work.mkdir(parents=True)
    tag = f"{os.getpid()}_{int(time.time())}"
    cache = f" --reference-cache {shlex.quote(str(work / 'cache'))}"

    r = Recipe(bokehbench, work / "recipe", recipe, SWEEP + QUICK + cache, Store(host, user, f"slurm_recipe_{tag}"))
    # The unsharded run of the same configuration (it also fills the reference cache the tasks share).
    run([bokehbench, *shlex.split(r.sweep), "--out-dir", str(r.work / "whole"), "--no-store"])
    r.submit()
    check_recipe(r, bokehbench, schema_dir, validate)
    check_duplicate(r, bokehbench)

    c = Recipe(bokehbench, work / "cancelled", recipe, SWEEP + SLOW + cache, Store(host, user, f"slurm_cancel_{tag}"))
    c.submit()
    check_cancelled(c, bokehbench)
    log("PASS")
    return 0


if __name__ == "__main__":
    if len(sys.argv) != 6:
        sys.exit(__doc__)
    sys.exit(main(*sys.argv[1:]))
