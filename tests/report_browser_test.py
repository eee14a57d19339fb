#!/usr/bin/python3
"""The history end to end: a real run imported as 12 commits with a known step (every sample x1.25 from
commit c07 on, and every naive/FLAG ratio with its interval x1.25: headline figures are series of their
own; the growth exponents stay as they were), its change points, and the HTML report opened in a real headless browser (Debian's
chromium): no console messages, every trend drawn, every plot decoded; a screenshot is kept.

usage: report_browser_test.py BOKEHBENCH WORKDIR REAL_RUN_JSON PLOTS_DIR
"""
import json
import pathlib
import re
import shutil
import subprocess
import sys

STEP_AT, FACTOR = 7, 1.25


def run(cmd, ok=(0,)):
    done = subprocess.run(cmd, capture_output=True, text=True, timeout=300)
    assert done.returncode in ok, f"{' '.join(map(str, cmd))}: exit {done.returncode}\n{done.stdout}\n{done.stderr}"
    return done


def chromium(args, page):
    """Runs headless chromium on a page; returns (stdout, console lines)."""
    exe = shutil.which("chromium") or shutil.which("chromium-browser")
    if exe is None:
        sys.exit("FAIL: chromium is not installed (apt-get install chromium; .ci/setup installs it)")
    done = subprocess.run([exe, "--headless", "--no-sandbox", "--disable-gpu", "--enable-logging=stderr", "--v=0",
                           *args, page.as_uri()], capture_output=True, text=True, timeout=120)
    console = [l for l in done.stderr.splitlines() if ":CONSOLE" in l]
    return done, console


def main(bokehbench, workdir, real_run, plots_dir):
    work = pathlib.Path(workdir)
    shutil.rmtree(work, ignore_errors=True)
    work.mkdir(parents=True)
    base = json.loads(pathlib.Path(real_run).read_text())
    files = []
    for c in range(12):
        doc = json.loads(json.dumps(base))
        doc["context"]["git_commit"] = f"c{c:02d}"
        doc["context"]["date_utc"] = f"2026-01-01T00:{c:02d}:00Z"
        factor = FACTOR if c >= STEP_AT else 1.0
        for p in doc["points"]:
            p["samples_ms"] = [v * factor for v in p["samples_ms"]]
            p["samples_cpu_ms"] = [v * factor for v in p["samples_cpu_ms"]]
        for r in doc["naive_over_flag"]:
            for key in ("naive_over_flag", "low", "high"):
                r[key] *= factor
        path = work / f"run{c:02d}.json"
        path.write_text(json.dumps(doc))
        files.append(str(path))
    store = work / "history.sqlite"
    run([bokehbench, "history", "import", "--store", str(store), *files])
    again = run([bokehbench, "history", "import", "--store", str(store), files[0]])
    assert "already in the store" in again.stdout, again.stdout

    # Every series steps at c07 by exactly the factor (the same samples, scaled).
    changes = work / "changes.json"
    run([bokehbench, "history", "changes", "--store", str(store), "--json", str(changes)])
    all_series = json.loads(changes.read_text())["series"]
    series = [s for s in all_series if not s["headline"]]
    ratios = [s for s in all_series if s["headline"] and s["point"].startswith("naive_over_flag/")]
    exponents = [s for s in all_series if s["headline"] and s["point"].startswith("exponent/")]
    assert len(series) == len(base["points"]), (len(series), len(base["points"]))
    assert len(ratios) == len(base["naive_over_flag"]) and ratios, (len(ratios), len(base["naive_over_flag"]))
    assert len(exponents) == sum(len(c["fits"]) for c in base["series"]) and exponents, len(exponents)
    probes = [s for s in all_series if s["headline"] and s["point"].startswith("probe/")]
    assert len(probes) == len(base["measurement"]["probes"]), len(probes)
    assert len(all_series) == len(series) + len(ratios) + len(exponents) + len(probes), [s["point"] for s in all_series]
    for s in series + ratios:
        assert len(s["steps"]) == 1, s
        step = s["steps"][0]
        assert step["commit"] == f"c{STEP_AT:02d}" and step["before_commit"] == f"c{STEP_AT - 1:02d}", step
        assert abs(step["ratio"] - FACTOR) < 1e-9, step
    for s in exponents + probes:  # unchanged over the 12 commits: no change point
        assert s["steps"] == [] and s["commits"] == 12 and s["unit"] in ("exponent", "ms"), s
    print(f"{len(series)} point series and {len(ratios)} naive/FLAG ratio series, each with its one step at "
          f"c{STEP_AT:02d} (x{FACTOR}); {len(exponents)} exponent series without one")
    one = run([bokehbench, "history", "series", "--store", str(store), "--point", ratios[0]["point"]]).stdout
    assert "headline figure (ratio)" in one and "95% interval" in one and "change point: +25.0%" in one, one

    page = work / "report.html"
    run([bokehbench, "report", "--store", str(store), "--out", str(page), "--plots-dir", plots_dir])
    html = page.read_text()
    assert "http://" not in html.replace('xmlns="http://www.w3.org/2000/svg"', "") and "https://" not in html, \
        "the page must be self-contained"
    done, console = chromium(["--dump-dom"], page)
    assert done.returncode == 0, done.stderr[-2000:]
    assert not console, "console messages:\n" + "\n".join(console)
    rendered = re.search(r'data-rendered="trends:(\d+) headlines:(\d+) images:(\d+)/(\d+)"', done.stdout)
    assert rendered, "the page's load check did not run"
    trends, headlines, loaded, images = map(int, rendered.groups())
    assert trends == len(all_series) and headlines == len(ratios) + len(exponents) + len(probes), (trends, headlines, len(all_series))
    assert images >= 1 and loaded == images, f"{loaded} of {images} plots decoded"
    print(f"chromium: {trends} trends drawn ({headlines} of headline figures), {loaded}/{images} plots decoded, no console messages")
    shot = work / "report.png"
    done, console = chromium([f"--screenshot={shot}", "--window-size=1200,2400", "--hide-scrollbars"], page)
    assert shot.exists() and shot.stat().st_size > 10000, "no screenshot"
    print(f"screenshot: {shot} (CI keeps it as an artifact)")

    # The console check is not vacuous: a page with an error is caught.
    bad = work / "bad.html"
    bad.write_text("<html><body><script>console.error('plot did not load: x');</script></body></html>")
    _, console = chromium(["--dump-dom"], bad)
    assert console, "a console error went unseen"


if __name__ == "__main__":
    if len(sys.argv) != 5:
        sys.exit(__doc__)
    main(*sys.argv[1:])
