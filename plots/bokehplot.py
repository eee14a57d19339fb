"""What every bokehbench plot shares: the context line, styles taken from the results themselves
(so a new method or precision is drawn without editing a table), saving PNG + SVG, argv."""
import json
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

MARKER_CYCLE = "osD^vP<>Xph*"


def context_line(doc):
    """Device, driver, threads, machine, date and commit, so a figure carries where it was measured."""
    ctx = doc["context"]
    device = ctx.get("device") or {}
    where = f"{device['name']} ({device.get('driver_info', '')})" if device else "CPU only"
    status = doc.get("status", "complete")
    return (f"{where}, LP_NUM_THREADS={ctx['lp_num_threads']}, {ctx['cpu_cores']} cores, {ctx['date_utc']}, "
            f"commit {ctx['git_commit']}" + ("" if status == "complete" else f"  [{status}]"))


def method_names(doc):
    """Methods in registry order (the results list them), then any others the points name."""
    names = [m["name"] for m in doc.get("methods", [])]
    for p in doc.get("points", []):
        if p["method"] not in names:
            names.append(p["method"])
    return names


def method_colours(doc):
    """One colour per method, in registry order."""
    names = method_names(doc)
    # tab10 without its grey, which the plots keep for legend entries that are not a method.
    palette = [c for i, c in enumerate(plt.get_cmap("tab10").colors) if i != 7]
    if len(names) > len(palette):
        palette = list(plt.get_cmap("tab20").colors)
    return {name: palette[i % len(palette)] for i, name in enumerate(names)}


def markers_for(values):
    """One marker per distinct value, in first-seen order."""
    out = {}
    for v in values:
        if v not in out:
            out[v] = MARKER_CYCLE[len(out) % len(MARKER_CYCLE)]
    return out


def save(fig, prefix):
    # Through a temporary name and a rename, as the results files: a run interrupted or racing another
    # never leaves a half-written plot.
    for ext in ("png", "svg"):
        tmp = f"{prefix}.tmp-{os.getpid()}.{ext}"
        fig.savefig(tmp, dpi=110, format=ext)
        os.replace(tmp, f"{prefix}.{ext}")
    print(f"wrote {prefix}.png and {prefix}.svg")


def run(main, doc_string):
    """usage: SCRIPT RESULTS_JSON OUT_PREFIX -> main(doc, prefix)."""
    if len(sys.argv) != 3:
        sys.exit(doc_string)
    with open(sys.argv[1]) as f:
        main(json.load(f), sys.argv[2])
