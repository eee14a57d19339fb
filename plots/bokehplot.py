"""What every bokehbench plot shares: the context line under the title, saving PNG + SVG, argv."""
import json
import sys

import matplotlib

matplotlib.use("Agg")


def context_line(doc):
    """Device, driver, threads, machine, date and commit, so a figure carries where it was measured."""
    ctx = doc["context"]
    device = ctx.get("device") or {}
    where = f"{device['name']} ({device.get('driver_info', '')})" if device else "CPU only"
    status = doc.get("status", "complete")
    return (f"{where}, LP_NUM_THREADS={ctx['lp_num_threads']}, {ctx['cpu_cores']} cores, {ctx['date_utc']}, "
            f"commit {ctx['git_commit']}" + ("" if status == "complete" else f"  [{status}]"))


def save(fig, prefix):
    for ext in ("png", "svg"):
        fig.savefig(f"{prefix}.{ext}", dpi=110)
    print(f"wrote {prefix}.png and {prefix}.svg")


def run(main, doc_string):
    """usage: SCRIPT RESULTS_JSON OUT_PREFIX -> main(doc, prefix)."""
    if len(sys.argv) != 3:
        sys.exit(doc_string)
    with open(sys.argv[1]) as f:
        main(json.load(f), sys.argv[2])
