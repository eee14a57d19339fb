#!/usr/bin/python3
"""Fault injection for every kind of file bokehbench writes: results JSON (compare --json), an image
(render --out, EXR and PNG) and a sweep's partial file (figure9's checkpoint), each over an existing file,
into a full disk and into a read-only folder. Each must exit non-zero with a message naming the path,
leave the existing file byte for byte, and leave no temporary (*.tmp.*).

Without root: the full disk is RLIMIT_FSIZE with SIGXFSZ ignored (writes past the limit fail with EFBIG,
as ENOSPC would); the read-only folder is a read-only bind mount in a user namespace (unshare -Urm), or,
where that is not allowed, a folder without write permission (which does not stop root).

usage: write_faults_test.py BOKEHBENCH WORKDIR
"""
import pathlib
import resource
import shutil
import signal
import subprocess
import sys

LIMIT_BYTES = 1024


def full_disk():
    signal.signal(signal.SIGXFSZ, signal.SIG_IGN)  # inherited through exec: a write fails instead of killing
    resource.setrlimit(resource.RLIMIT_FSIZE, (LIMIT_BYTES, resource.RLIM_INFINITY))


def read_only_runner(folder):
    """A prefix that runs a command with `folder` read-only, and how; None where neither way works."""
    probe = ["unshare", "-Urm", "sh", "-c", 'mount --bind "$0" "$0" && mount -o remount,bind,ro "$0" && exec "$@"',
             str(folder), "sh", "-c", f'! touch "{folder}/probe"']
    if shutil.which("unshare") and subprocess.run(probe, capture_output=True).returncode == 0:
        return probe[:6], "a read-only bind mount (unshare -Urm)"
    folder.chmod(0o555)
    try:
        (folder / "probe").touch()
    except PermissionError:
        return [], "a folder without write permission"
    (folder / "probe").unlink()
    folder.chmod(0o755)
    return None, "neither a user namespace nor permissions stop this user (root without unshare)"


def check_failed_write(what, command, target, named, preexec=None, prefix=()):
    before = target.read_bytes()
    done = subprocess.run(list(prefix) + command, capture_output=True, text=True, timeout=300, preexec_fn=preexec)
    out = done.stdout + done.stderr
    assert done.returncode != 0, f"{what}: exit 0\n{out}"
    assert done.returncode < 128 and done.returncode > 0, f"{what}: exit {done.returncode}\n{out}"
    assert f"'{named}'" in done.stderr, f"{what}: the message does not name '{named}'\n{out}"
    assert "result:" not in done.stdout, f"{what}: a verdict was printed by a run that failed\n{out}"
    assert target.read_bytes() == before, f"{what}: {target} changed"
    left = sorted(p.name for p in target.parent.glob("*.tmp.*"))
    assert not left, f"{what}: temporaries left: {left}"
    print(f"{what}: exit {done.returncode}, {target.name} intact, no temporary: "
          f"{done.stderr.strip().splitlines()[-1]}")


def main(bokehbench, workdir):
    work = pathlib.Path(workdir)
    if work.exists():
        for p in work.rglob("*"):
            if p.is_dir():
                p.chmod(0o755)
    shutil.rmtree(work, ignore_errors=True)
    out, cache = work / "out", work / "cache"
    out.mkdir(parents=True)
    sweep = [bokehbench, "figure9", "--quick", "--backends", "cpu", "--methods", "naive", "--sizes", "5",
             "--width", "32", "--height", "32", "--budget-s", "0.5", "--no-plot", "--cpu-threads", "1",
             "--out-dir", str(out), "--reference-cache", str(cache)]
    done = subprocess.run(sweep, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stdout + done.stderr
    results = out / "figure9.json"
    # Files that exist before each faulty write, larger than the limit or not: all must survive.
    shutil.copy(results, out / "figure9.partial.json")
    shutil.copy(results, out / "c.json")
    def render(scene):
        return [bokehbench, "render", "--scene", scene, "--width", "64", "--height", "64", "--backend", "cpu"]

    for name in ("old.exr", "old.png"):
        done = subprocess.run(render("points") + ["--out", str(out / name)], capture_output=True, text=True,
                              timeout=300)
        assert done.returncode == 0, done.stdout + done.stderr
    compare = [bokehbench, "compare", str(results), str(results), "--json", str(out / "c.json")]

    cases = [
        ("results JSON (compare --json)", compare, out / "c.json"),
        ("image (render --out, EXR)", render("hoops") + ["--out", str(out / "old.exr")], out / "old.exr"),
        ("image (render --out, PNG)", render("hoops") + ["--out", str(out / "old.png")], out / "old.png"),
        ("sweep partial file (figure9)", sweep, out / "figure9.partial.json"),
    ]
    for what, command, target in cases:
        check_failed_write(f"full disk, {what}", command, target, target, preexec=full_disk)
    assert (out / "figure9.json").read_bytes() == results.read_bytes()

    prefix, how = read_only_runner(out)
    if prefix is None:
        print(f"read-only folder: not tested here: {how}")
    else:
        print(f"read-only folder: {how}")
        try:
            for what, command, target in cases:
                # Refused before any work where the command checks its outputs first (naming the file or
                # its folder), or when the write fails.
                named = target if target.suffix != ".json" or "partial" not in target.name else target.parent
                check_failed_write(f"read-only folder, {what}", command, target, named, prefix=prefix)
        finally:
            out.chmod(0o755)
    print("every failed write left the old file and no temporary, and named its path")


if __name__ == "__main__":
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    main(sys.argv[1], sys.argv[2])
