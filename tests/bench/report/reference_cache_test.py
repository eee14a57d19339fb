#!/usr/bin/python3
"""A reference-cache entry replaced by another valid entry's file is recomputed, with a one-line note,
and the error reported (render --compare's PSNR, RMSE, ... lines) is the cold run's.

usage: reference_cache_test.py BOKEHBENCH WORKDIR
"""
import pathlib
import shutil
import subprocess
import sys


def main(bokehbench, workdir):
    work = pathlib.Path(workdir)
    shutil.rmtree(work, ignore_errors=True)
    work.mkdir(parents=True)
    cache = work / "cache"

    def render(scene):
        done = subprocess.run([bokehbench, "render", "--scene", scene, "--width", "32", "--height", "32",
                               "--backend", "cpu", "--compare", "--reference-cache", str(cache),
                               "--out", str(work / f"{scene}.exr")], capture_output=True, text=True, timeout=300)
        assert done.returncode == 0, done.stdout + done.stderr
        return [line for line in done.stdout.splitlines() if line.strip().startswith("vs_")], done.stderr

    cold, _ = render("points")
    entries = set(cache.iterdir())
    render("hoops")
    others = sorted(set(cache.iterdir()) - entries)
    assert len(entries) == 2 and len(others) == 2, (entries, others)
    # Each of points' entries (energy_sum, depth_ordered) replaced by hoops' entry of the same mode.
    for entry in entries:
        mode = entry.name.split("-")[1]
        shutil.copy([o for o in others if o.name.split("-")[1] == mode][0], entry)
    swapped, notes = render("points")
    assert swapped == cold, f"cold run:\n{cold}\nafter the swap:\n{swapped}"
    lines = [line for line in notes.splitlines() if line.startswith("note: reference cache entry")]
    assert len(lines) == 2 and all("was computed for other inputs" in line for line in lines), notes
    again, notes = render("points")
    assert again == cold and "note:" not in notes, notes
    print("swapped entries were recomputed:", *lines, sep="\n  ")


if __name__ == "__main__":
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    main(sys.argv[1], sys.argv[2])
